"""Which routines of the given KRL files keep $BASE and $TOOL across a call of them.

A routine keeps both when nothing in it changes them (``KrlScan.routines``: ``$BASE =``,
``$TOOL =``, ``FDAT_ACT =``, a ``BAS`` command other than the velocity, acceleration,
approximation, output and group ones, a motion's or spline block's ``WITH $BASE``/``$TOOL``)
and every routine it calls as a statement is in the given files and keeps both. The routines
that call each other (recursion) keep both unless one of them changes them: the answer is the
largest set of routines that call only routines of the set and change nothing themselves.

A call resolves as KRL resolves it: to a routine of the caller's own file (its module), else to
the one routine of that name among those other modules can call (``GLOBAL``, or a module's main
routine: the first of its .src). A routine not in the given files may change both.
"""

from __future__ import annotations

from pathlib import Path

from accugrid.codegen.krl.parse import KrlScan, Routine

__all__ = ["call_effects"]


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
    where = {
        id(r): (s, Path(scan.path or "").name)
        for s, scan in enumerate(scans)
        for r in scan.routines
    }

    def resolve(s: int, name: str) -> Routine | str:
        """The routine a call of ``name`` in scan s runs, or why it is not known."""
        found = local[s].get(name)
        if found is not None:
            return found
        others = [r for t, r in public.get(name, []) if t != s]
        if len(others) == 1:
            return others[0]
        if others:
            files = ", ".join(where[id(r)][1] for r in others)
            return f"is defined in more than one of the given files ({files})"
        return "may change $BASE"

    why = {
        id(r): f"changes $BASE or $TOOL ({r.sets} of {where[id(r)][1]})" if r.sets else ""
        for scan in scans
        for r in scan.routines
    }
    changed = True
    while changed:  # drop the keepers that call a routine that is not one, until none does
        changed = False
        for s, scan in enumerate(scans):
            for r in scan.routines:
                if why[id(r)]:
                    continue
                for name, line in r.calls:
                    callee = resolve(s, name.upper())
                    if isinstance(callee, str) or why[id(callee)]:
                        file = where[id(r)][1]
                        why[id(r)] = f"calls {name}() ({file}:{line}), which " + (
                            callee if isinstance(callee, str) else "changes $BASE or $TOOL"
                        )
                        changed = True
                        break
    out: list[dict[str, str] | None] = []
    for s, scan in enumerate(scans):
        called = {name.upper() for r in scan.routines for name, _ in r.calls}
        effects = {}
        for name in called:
            callee = resolve(s, name)
            if not isinstance(callee, str):
                effects[name] = why[id(callee)]
            elif callee != "may change $BASE":
                effects[name] = callee
        out.append(effects or None)
    return out
