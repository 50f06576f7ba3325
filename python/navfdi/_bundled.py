"""The scenarios shipped with navfdi (``navfdi/scenarios/*.toml``): their names and text."""

from __future__ import annotations

from importlib import resources


def bundled_toml(name: str) -> str:
    """The TOML text of the bundled scenario ``name`` (to read, or to copy and edit). Raises
    ``ValueError`` naming the bundled scenarios for an unknown name."""
    names = bundled_scenarios()
    if name not in names:
        raise ValueError(f"{name!r} is not a bundled scenario (bundled: {', '.join(names)})")
    return (resources.files("navfdi") / "scenarios" / f"{name}.toml").read_text(encoding="utf-8")


def bundled_scenarios() -> list[str]:
    """Names of the scenarios shipped with navfdi."""
    root = resources.files("navfdi") / "scenarios"
    return sorted(p.name[: -len(".toml")] for p in root.iterdir() if p.name.endswith(".toml"))
