"""The Jinja2 environment the program dialects are rendered with.

StrictUndefined (a misspelt variable is an error, never an empty string), no autoescaping (the
output is not HTML), and numbers and user text only through the ``infra.textsafe`` filters:
``fixed`` (numbers), ``comment`` (user text inside a comment), and a dialect's own (its names).
A template error (in a user's ``--templates`` copy) is an InputError naming the template file
and line.
"""

from __future__ import annotations

import contextlib
import functools
import os
import re
from collections.abc import Callable, Iterator
from pathlib import Path

import jinja2
import jinja2.meta

from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import note_input
from accugrid.infra.textsafe import comment_text, fixed
from accugrid.templates import TEMPLATE_DIR

__all__ = [
    "environment",
    "loaded",
    "printed_plainly",
    "render",
    "render_around",
    "template_dir",
    "template_uses",
]

_MARKER = "\x00accugrid lines\x00"  # no text of a program holds a NUL


def template_dir(dialect: str, templates: str | os.PathLike[str] | None = None) -> Path:
    """Folder of a dialect's templates: the built-in one, or ``templates`` (a copy of the whole
    templates folder holding ``<dialect>/``, or of the dialect folder itself)."""
    if templates is None:
        return TEMPLATE_DIR / dialect
    root = Path(templates)
    if not root.is_dir():
        raise InputError("--templates: not a folder", os.fspath(root))
    return root / dialect if (root / dialect).is_dir() else root


def environment(
    folder: Path, newline: str = "\n", filters: tuple[tuple[str, Callable], ...] = ()
) -> jinja2.Environment:
    """A strict environment loading from ``folder``; ``newline`` is the output line ending;
    ``filters``: the dialect's own (name, function) besides ``fixed`` and ``comment``. One per
    folder, line ending and filters in a process, so each template is compiled once (Jinja
    reloads a template whose file changed)."""
    note_input(folder)  # templates are inputs: no output may replace them
    return _environment(os.fspath(folder), newline, filters)


@functools.lru_cache(maxsize=16)
def _environment(
    folder: str, newline: str, filters: tuple[tuple[str, Callable], ...]
) -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(folder),
        undefined=jinja2.StrictUndefined,
        autoescape=False,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        newline_sequence=newline,
    )
    env.filters["fixed"] = fixed
    env.filters["comment"] = comment_text
    env.filters.update(filters)
    return env


def render(env: jinja2.Environment, template: str | jinja2.Template, /, **context: object) -> str:
    """Render ``template`` (a name, or one ``loaded`` for many files of a job); template and
    undefined-variable errors become InputErrors."""
    name = template if isinstance(template, str) else template.name
    with _template_errors(env, name):
        loaded = env.get_template(template) if isinstance(template, str) else template
        return loaded.render(**context)


def loaded(env: jinja2.Environment, template: str) -> jinja2.Template:
    """``template`` compiled once for the files of a job (Jinja checks a template's file for
    changes each time it is fetched by name); errors as InputErrors."""
    with _template_errors(env, template):
        return env.get_template(template)


def template_uses(env: jinja2.Environment, template: str) -> frozenset[str] | None:
    """Context variables ``template`` refers to, so that costly ones are built only when used;
    None (assume all) when it includes, imports or extends another template."""
    with _template_errors(env, template):
        source = env.loader.get_source(env, template)[0]
        tree = env.parse(source)
    if any(True for _ in jinja2.meta.find_referenced_templates(tree)):
        return None
    return frozenset(jinja2.meta.find_undeclared_variables(tree))


@contextlib.contextmanager
def _template_errors(env: jinja2.Environment, template: str) -> Iterator[None]:
    """Template and undefined-variable errors as InputErrors naming the template."""
    try:
        yield
    except jinja2.TemplateNotFound as exc:
        folder = env.loader.searchpath[0] if isinstance(env.loader, jinja2.FileSystemLoader) else ""
        raise InputError(f"template '{exc.name}' not found", folder) from None
    except jinja2.TemplateSyntaxError as exc:
        raise InputError(
            f"template syntax error: {exc.message}", exc.filename, exc.lineno
        ) from None
    except jinja2.UndefinedError as exc:
        raise InputError(f"template uses an undefined value: {exc.message}", template) from None


def printed_plainly(env: jinja2.Environment, template: str, name: str) -> bool:
    """Whether ``template`` prints the variable ``name`` and only as it is (``{{ name }}``,
    with or without whitespace control), never filtered, cut or measured: then its text can be
    rendered around the value (``render_around``) and the value put in between as bytes."""
    source = env.loader.get_source(env, template)[0]
    printed = re.findall(r"\{\{-?\s*" + re.escape(name) + r"\s*-?\}\}", source)
    return bool(printed) and len(printed) == source.count(name)


def render_around(
    env: jinja2.Environment, template: str | jinja2.Template, name: str, /, **context
) -> list[str]:
    """The text of ``template`` (which prints ``name`` plainly: ``printed_plainly``) cut where
    it prints ``name``: k + 1 pieces for k prints."""
    return render(env, template, **{name: _MARKER}, **context).split(_MARKER)
