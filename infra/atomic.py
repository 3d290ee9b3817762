"""Writing outputs safely: inputs are never replaced, a job's files appear whole or not at all.

Refused, with exit 2, even with ``--force``:

- a target that is one of the command's inputs: the same file (device and inode, so through
  symlinks and hard links) as a path the command was given, a file inside a given input folder
  (``--templates``), or any file the command read through ``infra.inputfile``;
- a target that exists and is not a regular file (``/dev/null``, a FIFO, a device, a folder);
- a target whose folder is a file.

Writing (``write_files``): every file goes first to a temporary file beside its target
(``.NAME.PID.RANDOM.accugrid.tmp``, NAME cut so the whole name fits in 255 bytes; created with the
umask's permissions). A job of several files writes its temporaries into one temporary folder of
that name inside each target folder, as ``NAME``. Every temporary is made durable (fsync, on a
background thread as soon as it is written) before anything is replaced.

All old or all new, SIGKILL and power loss included:

- A job of one file: one rename over the target.
- A job of several files into a folder that does not exist yet: written into a temporary folder
  beside it, synced, and renamed once into place; the folder appears whole.
- A job of several files otherwise is committed by a **journal**: once every temporary is
  durable, the list of the job's steps (remove the old entry point, rename each temporary over
  its target, delete the ``stale`` files, rename the ``main`` files last, in order) is written to
  ``journal`` in the temporary folder of the entry point's folder, fsynced, and that folder
  synced; the temporary folders in the job's other folders hold a ``link`` to it. Then the steps
  run, the target folders are synced, and the temporary folders removed (the journal last).
  Each step is guarded by its temporary still being there, so running the list again finishes
  the job from wherever it stopped.
- Recovery: every accugrid write (``check_targets`` and ``write_files``) first looks at the
  temporary folders of processes that no longer run in each folder it writes into: one with a
  journal (or a link to an existing journal) is finished, rolled forward to all new; anything
  else (killed before the journal was in place) is deleted, which leaves all old.

What a reader of a target folder sees: before the journal is in place, the old files only; after
the job or its recovery, the new files only (and no stale module). Between a kill during the
steps and the next accugrid write into one of the job's folders, the files may be a mix of old
and new, but the entry point (the last ``main`` file, e.g. ``NAME.src`` of a KRL job, the program
of a rewrite, the YAML of ``identify``) is absent: whoever starts from it never sees a mix. A job
whose folders were moved or renamed between the kill and the recovery is not recovered.

SIGTERM, SIGHUP and SIGINT are held from the journal to the end of the steps; before the journal
they end the write with the temporaries removed (exit 128 + signal). An error during the steps
(e.g. a folder made read-only meanwhile) leaves the journal for the next write to finish, and says
so.
"""

from __future__ import annotations

import contextlib
import errno
import os
import queue
import signal
import stat
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from accugrid.infra.errors import InputError
from accugrid.infra.inputfile import file_identities, tracked_inputs
from accugrid.infra.signals import TERMINATION_SIGNALS, Terminated, signals_raise

__all__ = ["JobFiles", "check_targets", "write_files"]

_TMP_SUFFIX = ".accugrid.tmp"
_JOURNAL = "journal"  # in a job's temporary folder: the job is committed
_LINK = "link"  # in the job's other temporary folders: the journal's path
_MAGIC = b"accugrid journal 1"
_NAME_MAX = 255  # bytes of one file name (Linux, macOS, Windows filesystems)
_PATH_MAX = 4096  # bytes of a path given to the system, with its final NUL (Linux)

PathLike = str | os.PathLike[str]


@dataclass
class JobFiles:
    """What a command's domain call hands back: the files of the job (path -> text or bytes,
    written together by ``write_files``), the inputs they must never replace, and the lines
    the command prints once they are written (``lines`` on stdout, ``warnings`` on stderr),
    and ``main``: the files among them renamed last, in order (``write_files``)."""

    files: dict[PathLike, bytes | str]
    inputs: list[PathLike | None] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    main: list[PathLike] = field(default_factory=list)


def _input_identities(inputs: Iterable[PathLike | None]) -> set[tuple[int, int]]:
    """(device, inode) of every input: given paths (a folder: every file in it) and the files
    read under ``track_inputs``."""
    found = set(tracked_inputs())
    for item in inputs:
        if item is not None:
            found |= file_identities(item)
    return found


def _kind(mode: int) -> str:
    kinds = {stat.S_IFDIR: "a folder", stat.S_IFIFO: "a FIFO", stat.S_IFCHR: "a device"}
    return kinds.get(stat.S_IFMT(mode), "not a regular file")


def _check_one(
    path: Path, input_ids: set[tuple[int, int]], force: bool, folders: set[Path] | None = None
) -> None:
    """Refuse ``path`` as an output (module docstring); ``folders``: folders already found
    usable, whose files skip that check (a KRL job has hundreds of files in one folder)."""
    where = os.fspath(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        if exc.errno == errno.ENOTDIR:  # a parent is a file: said below
            st = None
        else:
            raise InputError(f"cannot use as output: {exc.strerror or exc}", where) from None
    if st is not None:
        if (st.st_dev, st.st_ino) in input_ids:
            raise InputError("refusing to overwrite an input file", where)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(f"output exists and is {_kind(st.st_mode)}; refusing it", where)
        if not force:
            raise InputError("output exists (use --force to overwrite)", where)
    if folders is not None and path.parent in folders:
        return
    for parent in path.absolute().parents:
        try:
            pst = os.stat(parent)
        except OSError:
            continue
        if not stat.S_ISDIR(pst.st_mode):
            raise InputError(f"cannot create the output: {parent} is not a folder", where)
        break
    if folders is not None:
        folders.add(path.parent)


def check_targets(
    targets: Iterable[PathLike],
    inputs: Iterable[PathLike | None] = (),
    force: bool = False,
) -> None:
    """Refuse before any work is done: a target that is an input, exists without ``force``, is
    not a regular file, or cannot be created (see the module docstring). An interrupted job in
    the targets' folders is finished or removed first (``recover``)."""
    input_ids = _input_identities(inputs)
    targets = [Path(t) for t in targets]
    recover({t.parent for t in targets})
    for target in targets:
        _check_one(target, input_ids, force)


def recover(folders: Iterable[PathLike]) -> None:
    """Finish or remove the jobs that processes which no longer run left in ``folders`` (module
    docstring): a temporary folder with a journal, or a link to a journal that still exists, is
    rolled forward; every other temporary is deleted. InputError when a journal's steps cannot
    be run (the journal stays for the next attempt)."""
    for folder in folders:
        try:
            entries = list(os.scandir(folder))
        except OSError:
            continue
        for entry in entries:
            if not (entry.name.startswith(".") and entry.name.endswith(_TMP_SUFFIX)):
                continue
            parts = entry.name[: -len(_TMP_SUFFIX)].rsplit(".", 2)
            if len(parts) != 3 or not parts[1].isdigit() or _alive(int(parts[1])):
                continue
            journal = _journal_of(entry.path)
            if journal is not None:
                _finish(journal, folder)
            _remove(entry.path)


def _journal_of(holder: str) -> str | None:
    """The journal that commits the job of the temporary folder ``holder``: its own, or the one
    its link names, if it exists (None: not committed, or not a folder)."""
    own = os.path.join(holder, _JOURNAL)
    if os.path.isfile(own):
        return own
    try:
        with open(os.path.join(holder, _LINK), "rb") as file:
            linked = os.fsdecode(file.read())
    except OSError:
        return None
    return linked if os.path.isfile(linked) else None


def _remove(path: str) -> None:
    """Delete a temporary file or folder (with its files), if it is still there."""
    try:
        if stat.S_ISDIR(os.lstat(path).st_mode):
            for name in os.listdir(path):
                os.unlink(os.path.join(path, name))
            os.rmdir(path)
        else:
            os.unlink(path)
    except OSError:
        pass


def _alive(pid: int) -> bool:
    """Whether another process ``pid`` runs (our own pid on a leftover means a reused pid)."""
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold the termination signals (delivered after the block) while the renames run."""
    mask = getattr(signal, "pthread_sigmask", None)
    if mask is None:
        yield
        return
    old = mask(signal.SIG_BLOCK, TERMINATION_SIGNALS)
    try:
        yield
    finally:
        mask(signal.SIG_SETMASK, old)


def _temp_name(path: Path) -> str:
    """``.NAME.PID.RANDOM.accugrid.tmp`` beside ``path``, NAME cut to fit ``_NAME_MAX`` bytes."""
    # os.urandom(4).hex() is secrets.token_hex(4), without importing secrets (hmac, random)
    tail = f".{os.getpid()}.{os.urandom(4).hex()}{_TMP_SUFFIX}"
    name = os.fsencode(path.name)[: _NAME_MAX - 1 - len(tail)]
    return os.path.join(path.parent, "." + os.fsdecode(name) + tail)


def _write_temp(tmp: str, data: bytes | bytearray | str | Iterable[bytes | str]) -> None:
    """Create ``tmp`` with the data: bytes (or a bytearray), text (UTF-8), or an iterable of
    either, written in turn (a job's text in pieces)."""
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies
    try:
        for part in [data] if isinstance(data, (bytes, bytearray, str)) else data:
            view = memoryview(part.encode("utf-8") if isinstance(part, str) else part)
            while view:
                view = view[os.write(fd, view) :]
    finally:
        os.close(fd)


class _Durable:
    """fsync of files on one background thread, each as soon as it is written: the disk takes a
    file's data while the job makes the next ones, and the renames wait only for what is left
    (364 KRL files of a 1e5-hole job: ~0 s after the last write, against 0.09 s for one
    ``os.sync`` after all of them)."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._failed: tuple[OSError, PathLike] | None = None
        self._thread = threading.Thread(target=self._run, name="accugrid-fsync", daemon=True)
        self._thread.start()

    def add(self, path: str, target: PathLike) -> None:
        """Make the written file ``path`` (the temporary of ``target``) durable."""
        self._queue.put((path, target))

    def wait(self) -> None:
        """Return once every added file is on the disk; InputError naming the first that
        could not be synced."""
        self.close()
        if self._failed is not None:
            exc, target = self._failed
            raise InputError(f"cannot write: {exc.strerror or exc}", target)

    def close(self) -> None:
        """Stop the thread after the files added so far (again: no-op)."""
        if self._thread.is_alive():
            self._queue.put(None)
            self._thread.join()

    def _run(self) -> None:
        while (item := self._queue.get()) is not None:
            path, target = item
            if self._failed is not None:
                continue
            try:
                fd = os.open(path, os.O_RDONLY)
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)
            except OSError as exc:
                self._failed = (exc, target)


def _sync_folders(folders: set[Path]) -> None:
    for folder in folders:
        with contextlib.suppress(OSError):
            fd = os.open(folder, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)


def write_files(
    contents: Mapping[PathLike, bytes | str | Iterable[bytes | str]],
    inputs: Iterable[PathLike | None] = (),
    force: bool = False,
    main: Iterable[PathLike] = (),
    stale: Iterable[PathLike] = (),
    ready: Callable[[], None] | None = None,
) -> list[Path]:
    """Write every file of a job atomically; text is encoded as UTF-8 with newlines untouched.
    Each file's text is taken from ``contents`` when it is written, in order, and may come in
    pieces (an iterable of text), so a mapping that renders on demand (``krl.emit.KrlFiles``)
    or a text made block by block (``gcode.emit.gcode_text``) never holds the whole job.

    ``main``: targets among ``contents`` renamed last, in order (the entry point last), after
    their old versions and the ``stale`` files (leftovers of an earlier job of the same name,
    deleted unless rewritten) are removed. ``ready()``: the job's last check, called once every
    temporary is written and before any rename (e.g. waiting for work that ran beside the
    writing); its InputError ends the write like any other. Returns the written paths. On an
    error or signal before the renames the targets are left as they were and no temporary
    remains.
    """
    paths = {Path(t): t for t in contents}  # the text is fetched as it is written
    main_paths = [Path(p) for p in main]
    stale_paths = [Path(p) for p in stale if Path(p) not in paths]
    input_ids = _input_identities(inputs)
    folders = {p.parent for p in paths}
    recover(folders | {p.parent for p in stale_paths})
    usable: set[Path] = set()
    for path in list(paths) + stale_paths:
        _check_one(path, input_ids, force, usable)
    new_folder = next(iter(folders)) if len(folders) == 1 and len(paths) > 1 else None
    if new_folder is not None and os.path.lexists(new_folder):
        new_folder = None
    for folder in sorted({new_folder.parent} if new_folder is not None else folders):
        _make_folder(folder)
    if new_folder is not None:
        _write_new_folder(new_folder, paths, contents, ready)
        _sync_folders({new_folder, new_folder.parent})
        return list(paths)
    temps: dict[Path, str] = {}
    holders: dict[Path, str] = {}  # a job of several files: its temporaries' folder per folder
    durable = _Durable()
    committed, several = False, len(paths) > 1 or bool(stale_paths)
    try:
        with signals_raise():
            for path, key in paths.items():
                try:
                    temps[path] = _temp_path(path, holders if several else None)
                    _write_temp(temps[path], contents[key])
                except OSError as exc:
                    raise InputError(f"cannot write: {exc.strerror or exc}", path) from None
                durable.add(temps[path], path)
            if ready is not None:
                ready()
            durable.wait()
            with _signals_held():
                if not holders:  # one file: one rename
                    ((path, tmp),) = temps.items()
                    try:
                        os.replace(tmp, path)
                    except OSError as exc:
                        raise InputError(f"cannot replace: {exc.strerror or exc}", path) from None
                else:
                    journal = _commit(temps, main_paths, stale_paths, holders)
                    committed = True
                    _finish(journal, next(iter(paths)).parent)
    except Terminated as stop:
        raise SystemExit(128 + stop.signum) from None
    finally:
        durable.close()
        if not committed:
            for tmp in temps.values():
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
            for holder in holders.values():
                _remove(holder)
    _sync_folders(folders)
    return list(paths)


def _make_folder(folder: Path) -> None:
    """Create ``folder`` and its missing parents, one level at a time (a loop, not recursion:
    a path of thousands of levels is an ordinary error)."""
    longest = max((len(os.fsencode(part)) for part in folder.parts), default=0)
    if longest > _NAME_MAX:
        reason = f"a folder name longer than {_NAME_MAX} bytes"
    elif len(os.fsencode(folder)) >= _PATH_MAX:
        reason = f"a path longer than {_PATH_MAX - 1} bytes"
    else:
        reason = ""
    if reason:  # refused before any level is made
        raise InputError(f"cannot create the output folder: File name too long ({reason})", folder)
    missing = []
    for level in [folder, *folder.parents]:
        if os.path.isdir(level):
            break
        missing.append(level)
    try:
        for level in reversed(missing):
            with contextlib.suppress(FileExistsError):
                os.mkdir(level, 0o777)
            if not os.path.isdir(level):
                raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), level)
    except OSError as exc:
        raise InputError(
            f"cannot create the output folder: {exc.strerror or exc}", os.fspath(folder)
        ) from None


def _temp_path(path: Path, holders: dict[Path, str] | None) -> str:
    """Where ``path``'s temporary goes: beside it, or (``holders``: a job of several files) in a
    temporary folder made inside its folder on first use (``holders``: folder -> it), as
    ``NAME``. Creating hundreds of files in a folder that holds the previous job's files costs
    about four times as much as in an empty one (364 KRL files: 0.2 s against 0.05 s)."""
    if holders is None:
        return _temp_name(path)
    if path.parent not in holders:
        holders[path.parent] = _temp_name(path)  # known before it exists: always cleaned
        os.mkdir(holders[path.parent], 0o777)  # the umask applies
    return os.path.join(holders[path.parent], path.name)


def _write_new_folder(
    folder: Path, paths: dict[Path, PathLike], contents: Mapping, ready: Callable[[], None] | None
) -> None:
    """Write the files ``paths`` (all in ``folder``, which does not exist) into a temporary
    folder beside it, ``ready()``, sync, and rename that folder to ``folder``; on an error or
    signal before the rename, nothing of it remains."""
    recover([folder.parent])
    tmp = _temp_name(folder)  # known before it exists: always cleaned
    durable = _Durable()
    try:
        with signals_raise():
            try:
                os.mkdir(tmp, 0o777)  # the umask applies
                for path, key in paths.items():
                    _write_temp(os.path.join(tmp, path.name), contents[key])
                    durable.add(os.path.join(tmp, path.name), path)
            except OSError as exc:
                raise InputError(f"cannot write: {exc.strerror or exc}", folder) from None
            if ready is not None:
                ready()
            durable.wait()
            with _signals_held():
                try:
                    os.rename(tmp, folder)  # refused if a non-empty folder appeared meanwhile
                except OSError as exc:
                    raise InputError(f"cannot create: {exc.strerror or exc}", folder) from None
    except Terminated as stop:
        raise SystemExit(128 + stop.signum) from None
    finally:
        durable.close()
        _remove(tmp)


def _commit(
    temps: dict[Path, str], main: list[Path], stale: list[Path], holders: dict[Path, str]
) -> str:
    """Write the job's journal (its steps, module docstring) durably into the temporary folder
    of the entry point's folder, with a link to it in the other temporary folders; returns its
    path. The job is committed once this returns."""
    last = [p for p in main if p in temps]
    steps: list[bytes] = []
    if last:  # the old entry point goes first (while its temporary waits)
        steps += [b"U", os.fsencode(last[-1]), os.fsencode(temps[last[-1]])]
    for path, tmp in temps.items():
        if path not in last:
            steps += [b"R", os.fsencode(tmp), os.fsencode(path)]
    for path in stale:
        steps += [b"D", os.fsencode(path)]
    for path in last:
        steps += [b"R", os.fsencode(temps[path]), os.fsencode(path)]
    home = holders[last[-1].parent] if last else next(iter(holders.values()))
    others = [h for h in holders.values() if h != home]
    steps += [x for h in others for x in (b"H", os.fsencode(os.path.abspath(h)))]
    journal = os.path.abspath(os.path.join(home, _JOURNAL))
    _sync_folders({Path(h).parent for h in holders.values()})  # the temporary folders' entries
    for holder in others:
        _write_synced(os.path.join(holder, _LINK), os.fsencode(journal))
    _write_synced(journal + ".new", b"\0".join([_MAGIC, *steps, b"END"]))
    os.rename(journal + ".new", journal)
    _sync_folders({Path(home)})
    return journal


def _write_synced(path: str, data: bytes) -> None:
    """Create ``path`` with ``data``, fsynced, and sync its folder."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
        os.fsync(fd)
    finally:
        os.close(fd)
    _sync_folders({Path(path).parent})


def _finish(journal: str, where: PathLike) -> None:
    """Run the steps of ``journal`` (each guarded: again after a kill finishes the job), sync
    the target folders, remove the job's other temporary folders, then the journal. InputError
    (naming ``where``) when a step fails: the journal stays for the next write."""
    try:
        with open(journal, "rb") as file:
            words = file.read().split(b"\0")
    except OSError as exc:
        raise InputError(
            f"cannot read an interrupted job's journal {journal}: {exc}", where
        ) from None
    if words[:1] != [_MAGIC] or words[-1:] != [b"END"]:
        raise InputError(f"unreadable journal of an interrupted job: {journal}", where)
    words = [os.fsdecode(w) for w in words[1:-1]]
    arity = {"U": 2, "R": 2, "D": 1, "H": 1}
    folders: set[Path] = set()
    others: list[str] = []
    at = 0
    try:
        while at < len(words):
            op, args = words[at], words[at + 1 : at + 1 + arity[words[at]]]
            at += 1 + len(args)
            if op == "U" and os.path.lexists(args[1]):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(args[0])
            elif op == "R" and os.path.lexists(args[0]):
                os.replace(args[0], args[1])
            elif op == "D":
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(args[0])
            elif op == "H":
                others.append(args[0])
            if op != "H":
                folders.add(Path(args[1] if op == "R" else args[0]).parent)
    except (KeyError, IndexError):
        raise InputError(f"unreadable journal of an interrupted job: {journal}", where) from None
    except OSError as exc:
        raise InputError(
            f"cannot replace: {exc.strerror or exc}; the next accugrid write into this folder "
            "finishes the job",
            exc.filename or where,
        ) from None
    _sync_folders(folders)
    for holder in others:
        _remove(holder)
    home = os.path.dirname(journal)
    with contextlib.suppress(OSError):
        os.unlink(journal)
    _remove(home)
