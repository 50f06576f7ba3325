"""The scenarios shipped with navfdi (``navfdi/scenarios/*.toml``): their names and text."""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def bundled_toml(name: str) -> str:
    """The TOML text of the bundled scenario ``name`` (to read, or to copy and edit). Raises
    ``ValueError`` naming the bundled scenarios for an unknown name."""
    names = bundled_scenarios()
    if name not in names:
        raise ValueError(f"{name!r} is not a bundled scenario (bundled: {', '.join(names)})")
    return (resources.files("navfdi") / "scenarios" / f"{name}.toml").read_text(encoding="utf-8")


def exported_toml(name: str) -> str:
    """:func:`bundled_toml` for a copy written elsewhere: its relative data paths (``"../…"``,
    relative to the bundled scenarios' folder) made absolute, so that the copy runs from
    wherever it is saved."""
    import re

    base = Path(str(resources.files("navfdi") / "scenarios"))

    def absolute(m: re.Match[str]) -> str:
        return '"' + (base / m.group(1)).resolve().as_posix() + '"'

    return re.sub(r'"(\.\./[^"\n]+)"', absolute, bundled_toml(name))


def bundled_scenarios() -> list[str]:
    """Names of the scenarios shipped with navfdi."""
    root = resources.files("navfdi") / "scenarios"
    return sorted(p.name[: -len(".toml")] for p in root.iterdir() if p.name.endswith(".toml"))
