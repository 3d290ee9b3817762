"""Which routines of the given KRL files keep $BASE and $TOOL across a call of them.

A routine keeps both when nothing in it changes them (``KrlScan.routines``: ``$BASE =``,
``$TOOL =``, ``FDAT_ACT =``, a ``BAS`` command other than the velocity, acceleration,
approximation, output and group ones, a motion's or spline block's ``WITH $BASE``/``$TOOL``)
and every routine it calls as a statement is in the given files and keeps both, and so does
every routine of the given files it calls in an expression (a function; a name called there
that is not in the given files is taken for a built-in one, as the statement reader takes it).
The routines that call each other (recursion) keep both unless one of them changes them: the
answer is the largest set of routines that call only routines of the set and change nothing
themselves.

A call resolves as KRL resolves it: to a routine of the caller's own file (its module), else to
the one routine of that name among those other modules can call (``GLOBAL``, or a module's main
routine: the first of its .src). A routine not in the given files may change both.

A local routine (neither ``GLOBAL`` nor its module's main routine) runs only where its module
calls it: when every call of it has the same known base and tool, and no ``TRIGGER`` or
``INTERRUPT`` runs it (they run it wherever the robot is), it starts in them
(``routine_starts``); otherwise its start is its caller's, not known here.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from accugrid.codegen.krl.parse import BaseRef, KrlScan, Routine

__all__ = ["call_effects", "routine_starts"]

_NOT_GIVEN = "may change $BASE"  # why a call of a routine not in the given files may change it


def call_effects(scans: list[KrlScan]) -> list[dict[str, str] | None]:
    """Per scan, what each routine it calls does to $BASE and $TOOL: called name (upper case) ->
    "" when the routine keeps both, else why it may change them (the rest of "after the call
    F() at line n, which ..."); None for a scan that calls no routine of the given files."""
    local = [{r.name: r for r in scan.routines} for scan in scans]
    public: dict[str, list[tuple[int, Routine]]] = {}
    for s, scan in enumerate(scans):
        for r in scan.routines:
            if r.public:
                public.setdefault(r.name, []).append((s, r))
    file = {id(r): Path(scan.path or "").name for scan in scans for r in scan.routines}

    def resolve(s: int, name: str) -> Routine | str:
        """The routine a call of ``name`` in scan s runs, or why it is not known."""
        found = local[s].get(name)
        if found is not None:
            return found
        others = [r for t, r in public.get(name, []) if t != s]
        if len(others) == 1:
            return others[0]
        if others:
            files = ", ".join(file[id(r)] for r in others)
            return f"is defined in more than one of the given files ({files})"
        return _NOT_GIVEN

    # why each routine that is no keeper changes them: its own statement, else a call of a
    # routine not known, else (spread from callee to caller) a call of a routine that does
    why = {
        id(r): f"changes $BASE or $TOOL ({r.sets} of {file[id(r)]})"
        for scan in scans
        for r in scan.routines
        if r.sets
    }
    callers: dict[int, list[tuple[Routine, str, int]]] = {}
    for s, scan in enumerate(scans):
        for r in scan.routines:
            calls = [(name, line, True) for name, line in r.calls]
            calls += [(name, line, False) for name, line in r.uses]
            for name, line, statement in calls:
                callee = resolve(s, name.upper())
                if isinstance(callee, Routine):
                    callers.setdefault(id(callee), []).append((r, name, line))
                elif statement or callee != _NOT_GIVEN:  # else a built-in function
                    why.setdefault(id(r), f"calls {name}() ({file[id(r)]}:{line}), which {callee}")
    spread = [r for scan in scans for r in scan.routines if id(r) in why]
    while spread:
        callee = spread.pop()
        for r, name, line in callers.get(id(callee), ()):
            if id(r) not in why:
                why[id(r)] = f"calls {name}() ({file[id(r)]}:{line}), which changes $BASE or $TOOL"
                spread.append(r)
    out: list[dict[str, str] | None] = []
    for s, scan in enumerate(scans):
        effects = {}
        for name in {name.upper() for r in scan.routines for name, _ in r.calls}:
            callee = resolve(s, name)
            if isinstance(callee, Routine):
                effects[name] = why.get(id(callee), "")
            elif callee != _NOT_GIVEN:
                effects[name] = callee
        for name in {name.upper() for r in scan.routines for name, _ in r.uses}:
            callee = resolve(s, name)
            found = why.get(id(callee), "") if isinstance(callee, Routine) else callee
            if found and found != _NOT_GIVEN:
                effects[name] = found
        out.append(effects or None)
    return out


def routine_starts(scans: list[KrlScan]) -> list[dict[str, BaseRef]]:
    """Per scan, the base each of its local routines starts in (name, upper case -> the base
    and tool in effect at every call of it, when they are one and known)."""
    out = []
    for scan in scans:
        at: dict[str, set[BaseRef]] = {}
        for name, _, base in scan.call_sites:
            at.setdefault(name, set()).add(_start(base))
        starts = {}
        for r in scan.routines:
            found = at.get(r.name)
            if r.public or r.name in scan.async_calls or found is None or len(found) != 1:
                continue
            (base,) = found
            if base.kind != "unknown":
                starts[r.name] = base
        out.append(starts)
    return out


def _start(base: BaseRef) -> BaseRef:
    """``base`` as a routine's start: what it is, not where it was set."""
    return replace(base, line=0, reason="", label=None, tool_label=None, origin=None)
