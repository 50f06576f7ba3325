"""Console text at most 100 characters wide: prose lines longer than that are wrapped with
their indentation kept (tables are laid out to fit on their own)."""

from __future__ import annotations

import textwrap

#: Widest console line navfdi prints.
WIDTH = 100


def fit(text: str, width: int = WIDTH) -> str:
    """``text`` with every line longer than ``width`` wrapped at spaces, continuation lines
    indented two spaces more than the line they continue; shorter lines unchanged."""
    out = []
    for line in text.split("\n"):
        if len(line) <= width:
            out.append(line)
            continue
        indent = line[: len(line) - len(line.lstrip(" "))]
        out.extend(textwrap.wrap(line.strip(), width=width, initial_indent=indent, subsequent_indent=indent + "  ", break_long_words=False, break_on_hyphens=False) or [line])
    return "\n".join(out)
