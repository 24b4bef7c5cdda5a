"""The loader's warnings about a gate result: one line per kind of defect (count, names...)."""

from __future__ import annotations

import re

__all__ = ["defect_lines", "first_names", "mesh_lines"]


def first_names(names: list[str], limit: int = 3) -> str:
    """The first ``limit`` names, comma-separated, with ``…`` when there are more."""
    return ", ".join(names[:limit]) + (", …" if len(names) > limit else "")


#: Kinds of implausible inertials, by the words of the gate's message, and their one line.
_DEFECT_KINDS = (
    ("triangle inequality", "violate the triangle inequality I1 + I2 ≥ I3"),
    ("indefinite", "have an indefinite inertia"),
    ("not positive", "have an inertia that is not positive definite"),
    ("mass > 0", "are moving bodies that have no mass"),
    ("radius of gyration", "have a radius of gyration far beyond the robot's size"),
)


def defect_lines(defects: tuple[tuple[str, str], ...]) -> list[str]:
    """One line per kind of defect: count, the first few links, what to do."""
    kinds: dict[str, list[str]] = {}
    first: dict[str, str] = {}
    for link, why in defects:
        text = next((t for key, t in _DEFECT_KINDS if key in why), "have implausible inertials")
        names = kinds.setdefault(text, [])
        found = re.search(r"line (\d+)", why)
        first.setdefault(text, f"line {found.group(1)}" if found else "an unknown line")
        if link not in names:
            names.append(link)
    return [
        f"inertia: {len(names)} link(s) {text} ({first_names(names)}; first at {first[text]}); "
        "kinematics ignores them, dynamics refuses them: load with inertia='collision' or "
        "'point' (CLI: --inertia)"
        for text, names in kinds.items()
    ]


def mesh_lines(missing: tuple[tuple[str, str], ...]) -> list[str]:
    """One line per kind of unusable file (refused, empty, not found): count, first few, why."""
    groups: dict[tuple[str, str], list[str]] = {}
    line_of: dict[tuple[str, str], str] = {}
    for uri, why in missing:
        where, _, rest = why.partition(": ") if why.startswith("line ") else ("", "", why)
        kind, _, reason = rest.removeprefix(f"{uri!r}: ").partition(": ")
        if kind not in ("refused", "not found", "empty"):
            kind, reason = "not found", rest
        if kind == "not found" and reason.endswith("does not exist"):
            reason = "file does not exist"
        names = groups.setdefault((kind, reason), [])
        line_of.setdefault((kind, reason), where)
        if uri not in names:
            names.append(uri)
    out = []
    for (kind, reason), uris in groups.items():
        folder = uris[0].rsplit("/", 1)[0] + "/" if "/" in uris[0] else ""
        if len(uris) > 1 and folder and all(u.startswith(folder) for u in uris[:3]):
            shown = f"{first_names([u[len(folder) :] for u in uris])} in {folder}"
        else:
            shown = first_names([u if len(u) <= 60 else "…/" + u.rsplit("/", 1)[-1] for u in uris])
        where = line_of[(kind, reason)] or "an unknown line"
        out.append(
            f"meshes: {len(uris)} file(s) {kind}, their visual/collision elements dropped "
            f"({shown}; first at {where}): {reason}"
        )
    return out
