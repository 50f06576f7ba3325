"""Write ``docs/reference/api.md``: one mkdocstrings entry per public name of ``navfdi``
(``navfdi.__all__``), at the module that defines it (the compiled core's names are read from
its stubs, ``navfdi/_core.pyi``), grouped by module. ``tests/test_docs_site.py`` checks the file
is what this script writes.

Usage: ``python docs/scripts/api_reference.py [--check]``.
"""

from __future__ import annotations

import sys
from collections import defaultdict
from pathlib import Path

import navfdi

OUT = Path(__file__).resolve().parents[1] / "reference" / "api.md"

TITLES = {
    "navfdi._core": "Filters, detectors and statistics (compiled core)",
    "navfdi.scenario": "Scenarios",
    "navfdi.runs": "Runs",
    "navfdi.montecarlo": "Monte-Carlo campaigns",
    "navfdi.gnss": "Real GNSS data",
    "navfdi.integrity": "Integrity",
    "navfdi._bundled": "Bundled scenarios",
    "navfdi._errors": "Errors and warnings",
    "navfdi._filter": "Filter helpers",
    "navfdi._intervals": "Confidence intervals",
    "navfdi.frames": "IMU axes and mounting",
}


def text() -> str:
    by_module: dict[str, list[str]] = defaultdict(list)
    for name in navfdi.__all__:
        if name.startswith("__"):
            continue
        obj = getattr(navfdi, name)
        module = getattr(obj, "__module__", None) or "navfdi"
        if not module.startswith("navfdi"):
            module = "navfdi"
        by_module[module].append(name)
    lines = [
        "# Python API",
        "",
        "Every public name of `navfdi` (`navfdi.__all__`), generated from the docstrings and, for the",
        "compiled core, from its stubs (`navfdi/_core.pyi`) by `docs/scripts/api_reference.py`.",
        "",
    ]
    for module in sorted(by_module, key=lambda m: (m != "navfdi._core", m)):
        lines += [f"## {TITLES.get(module, module)}", "", f"`{module}`", ""]
        for name in by_module[module]:
            lines += [f"::: {module}.{name}", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    if "--check" in sys.argv:
        sys.exit(0 if OUT.read_text(encoding="utf-8") == text() else 1)
    OUT.write_text(text(), encoding="utf-8")
