"""JSON for the files navfdi writes: strict JSON that any parser reads.

Python's ``json`` writes NaN and infinities as the bare tokens ``NaN`` / ``Infinity``, which are
not JSON; every ``summary.json`` and ``campaign.json`` goes through :func:`dumps`, which writes
them as ``null`` (NaN: no value) or the strings ``"inf"`` / ``"-inf"``, and converts numpy
scalars and arrays.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np


def clean(obj: Any) -> Any:
    """A copy of ``obj`` (dicts, lists, tuples, numpy values, scalars) that strict JSON can hold."""
    if isinstance(obj, dict):
        return {str(k): clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return clean(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        if math.isnan(v):
            return None
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    return obj


def dumps(obj: Any, default: Any = str) -> str:
    """Strict JSON of ``obj`` (NaN → ``null``, ±inf → ``"inf"``/``"-inf"``), indented by 2."""
    return json.dumps(clean(obj), indent=2, default=default, allow_nan=False)
