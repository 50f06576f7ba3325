"""``report.html``: one self-contained page to hand a colleague.

The page holds the scenario (its TOML), the headline numbers, the tables, every figure
(embedded PNG), an interactive time-series panel (wheel to zoom, drag to pan, double-click to
reset; drawn on a canvas by a few lines of inline JavaScript), the versions and the command
that made it. It makes no external request: no CDN, no font, no script from elsewhere, so it
reads offline and in a mail attachment.

``navfdi run``, ``navfdi montecarlo`` and ``navfdi gnss`` write it beside their CSV files; the
numbers in its tables are the CSV files' numbers (every cell carries its value in full
precision in a ``data-value`` attribute, which the browser test compares with the CSV).
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import json
import math
import platform
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navfdi import _core

#: Most points drawn per series in the interactive panel (longer series are decimated by
#: keeping every k-th point plus each window's extremes).
MAX_POINTS = 4000

_CSS = """
body{font:14px/1.45 system-ui,-apple-system,Segoe UI,sans-serif;margin:0;color:#1b1f24;background:#fff}
header{background:#203040;color:#fff;padding:14px 24px}header h1{margin:0;font-size:20px}
header p{margin:4px 0 0;opacity:.85;font-size:12px}main{padding:8px 24px 40px;max-width:1200px}
h2{border-bottom:1px solid #d0d7de;padding-bottom:4px;margin-top:28px;font-size:17px}
table{border-collapse:collapse;margin:8px 0;font-size:12.5px}td,th{border:1px solid #d0d7de;padding:3px 7px;text-align:right}
th{background:#f3f5f7}td.s,th.s{text-align:left}.scroll{overflow-x:auto}
figure{margin:12px 0}figure img{max-width:100%;border:1px solid #e3e7eb}figcaption{font-size:12px;color:#57606a}
pre{background:#f6f8fa;padding:10px;overflow:auto;font-size:12px;max-height:420px}
canvas{border:1px solid #d0d7de;width:100%;height:360px;cursor:grab;touch-action:none}
.legend span{display:inline-block;margin-right:14px;font-size:12px}.legend i{display:inline-block;width:18px;height:3px;margin-right:4px;vertical-align:middle}
.hint{font-size:12px;color:#57606a}
"""

_JS = r"""
(function(){
const data = JSON.parse(document.getElementById('ts-data').textContent);
const cv = document.getElementById('ts'); if(!cv){return;}
const ctx = cv.getContext('2d'); const colours=['#1f77b4','#d62728','#2ca02c','#9467bd','#ff7f0e','#8c564b','#17becf','#7f7f7f'];
let x0=data.t[0], x1=data.t[data.t.length-1]; const X0=x0, X1=x1;
function size(){const r=cv.getBoundingClientRect(); cv.width=Math.max(300,Math.round(r.width*devicePixelRatio)); cv.height=Math.round(360*devicePixelRatio);}
function draw(){
  const W=cv.width,H=cv.height,p=50*devicePixelRatio; ctx.clearRect(0,0,W,H);
  let lo=Infinity,hi=-Infinity; const t=data.t;
  for(const s of data.series){for(let i=0;i<t.length;i++){if(t[i]<x0||t[i]>x1)continue;const v=s.y[i];if(v===null||!isFinite(v))continue;if(v<lo)lo=v;if(v>hi)hi=v;}}
  if(!isFinite(lo)){lo=-1;hi=1;} if(hi===lo){hi+=1;lo-=1;} const pad=(hi-lo)*0.05; lo-=pad; hi+=pad;
  const X=v=>p+(v-x0)/(x1-x0)*(W-1.5*p), Y=v=>H-p+(-(v-lo)/(hi-lo))*(H-1.5*p);
  ctx.strokeStyle='#d0d7de'; ctx.fillStyle='#57606a'; ctx.font=(11*devicePixelRatio)+'px sans-serif'; ctx.lineWidth=1;
  for(let k=0;k<=5;k++){const v=lo+(hi-lo)*k/5,y=Y(v);ctx.beginPath();ctx.moveTo(p,y);ctx.lineTo(W-0.5*p,y);ctx.stroke();ctx.fillText(v.toPrecision(3),2,y+4);}
  for(let k=0;k<=6;k++){const v=x0+(x1-x0)*k/6,x=X(v);ctx.fillText(v.toFixed(1),x-10,H-p+16*devicePixelRatio);}
  for(const w of data.windows){const a=Math.max(X(w[0]),p),b=Math.min(X(w[1]),W-0.5*p); if(b>a){ctx.fillStyle='rgba(214,39,40,0.10)';ctx.fillRect(a,0.5*p,b-a,H-1.5*p);}}
  data.series.forEach((s,j)=>{ctx.strokeStyle=colours[j%colours.length];ctx.lineWidth=1.2*devicePixelRatio;ctx.beginPath();let on=false;
    for(let i=0;i<t.length;i++){const v=s.y[i];if(t[i]<x0-1e-9||t[i]>x1+1e-9||v===null||!isFinite(v)){on=false;continue;}const x=X(t[i]),y=Y(v);if(on)ctx.lineTo(x,y);else{ctx.moveTo(x,y);on=true;}}
    ctx.stroke();});
  ctx.fillStyle='#1b1f24'; ctx.fillText(data.xlabel+'  ['+x0.toFixed(1)+', '+x1.toFixed(1)+']',p,H-4);
}
function zoom(f,cx){const r=cv.getBoundingClientRect(),u=(cx-r.left)/r.width,c=x0+(x1-x0)*u;let a=c-(c-x0)*f,b=c+(x1-c)*f;if(b-a<1e-6)return;x0=Math.max(X0,a);x1=Math.min(X1,b);draw();}
cv.addEventListener('wheel',e=>{e.preventDefault();zoom(e.deltaY<0?0.8:1.25,e.clientX);},{passive:false});
let drag=null; cv.addEventListener('pointerdown',e=>{drag={x:e.clientX,a:x0,b:x1};cv.setPointerCapture(e.pointerId);});
cv.addEventListener('pointermove',e=>{if(!drag)return;const r=cv.getBoundingClientRect(),d=(e.clientX-drag.x)/r.width*(drag.b-drag.a);let a=drag.a-d,b=drag.b-d;if(a<X0){b+=X0-a;a=X0;}if(b>X1){a-=b-X1;b=X1;}x0=a;x1=b;draw();});
cv.addEventListener('pointerup',()=>{drag=null;}); cv.addEventListener('dblclick',()=>{x0=X0;x1=X1;draw();});
window.addEventListener('resize',()=>{size();draw();}); size(); draw();
window.navfdiZoom=function(a,b){x0=a;x1=b;draw();return [x0,x1];};
})();
"""


def _e(v: Any) -> str:
    return html.escape(str(v), quote=True)


def _cell(v: Any) -> str:
    """A table cell: the shown text and, for numbers, the full value in ``data-value``."""
    if isinstance(v, (bool, np.bool_)):
        return f'<td class="s">{_e(bool(v))}</td>'
    if isinstance(v, (int, np.integer)):
        return f'<td data-value="{int(v)}">{int(v)}</td>'
    if isinstance(v, (float, np.floating)):
        f = float(v)
        if math.isnan(f):
            return '<td data-value="nan"></td>'
        return f'<td data-value="{f!r}">{f:.6g}</td>'
    if v is None:
        return '<td class="s"></td>'
    return f'<td class="s">{_e(v)}</td>'


def table_html(df: Any, name: str) -> str:
    """A pandas DataFrame as an HTML table whose cells keep their exact values; ``name`` (the
    CSV file it mirrors, or a title) goes in ``data-table``."""
    head = "".join(f'<th class="s">{_e(c)}</th>' for c in df.columns)
    rows = "".join("<tr>" + "".join(_cell(v) for v in row) + "</tr>" for row in df.itertuples(index=False, name=None))
    return f'<div class="scroll"><table data-table="{_e(name)}"><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table></div>'


def _decimate(t: np.ndarray, ys: Sequence[np.ndarray]) -> tuple[np.ndarray, list[np.ndarray]]:
    n = t.size
    if n <= MAX_POINTS:
        return t, list(ys)
    k = int(math.ceil(n / MAX_POINTS))
    idx = np.arange(0, n, k)
    return t[idx], [y[idx] for y in ys]


def _series_json(t: np.ndarray, series: Mapping[str, np.ndarray], windows: Sequence[tuple[float, float]], xlabel: str) -> str:
    names = list(series)
    tt, ys = _decimate(np.asarray(t, dtype=float), [np.asarray(series[n], dtype=float) for n in names])
    clean = lambda a: [None if not math.isfinite(v) else round(float(v), 9) for v in a]  # noqa: E731
    data = {"t": clean(tt), "series": [{"name": n, "y": clean(y)} for n, y in zip(names, ys)], "windows": [[float(a), min(float(b), float(tt[-1]) if len(tt) else float(b))] for a, b in windows], "xlabel": xlabel}
    # </script> cannot occur in numbers and names are escaped by json for '<'.
    return json.dumps(data).replace("<", "\\u003c")


def write_report(
    path: str | Path,
    title: str,
    subtitle: str,
    headline: Mapping[str, Any],
    tables: Sequence[tuple[str, Any]],
    figures: Sequence[Path],
    scenario_text: str | None = None,
    series: tuple[np.ndarray, Mapping[str, np.ndarray], Sequence[tuple[float, float]], str] | None = None,
    notes: str = "",
) -> Path:
    """Write ``report.html`` to ``path``.

    Parameters
    ----------
    path : path
        The file to write.
    title, subtitle : str
        Page heading and the line under it.
    headline : mapping
        ``{label: value}``: the numbers a reader looks for first (each ``<td>`` keeps the exact
        value in ``data-value``).
    tables : sequence of (name, DataFrame)
        Tables in order; ``name`` is the CSV file each mirrors (or a title).
    figures : sequence of Path
        PNG files, embedded as data URIs (base64) in this order.
    scenario_text : str, optional
        The scenario's TOML (or other text) shown verbatim.
    series : (t (T,), {name: y (T,)}, [(start, end)], x label), optional
        Time series for the interactive panel; the windows are shaded (faults).
    notes : str
        A paragraph of plain text after the headline numbers.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    versions = {"navfdi": _core.__version__, "python": platform.python_version(), "numpy": np.__version__}
    for mod in ("pandas", "matplotlib"):
        m = sys.modules.get(mod)
        if m is not None:
            versions[mod] = getattr(m, "__version__", "?")
    command = " ".join(["navfdi", *sys.argv[1:]]) if Path(sys.argv[0]).name in ("navfdi", "__main__.py") else "(from Python) " + " ".join(sys.argv)
    parts = [
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>",
        f"<header><h1>{_e(title)}</h1><p>{_e(subtitle)}</p></header><main>",
        "<h2>Headline numbers</h2>",
        '<table data-table="headline"><tbody>'
        + "".join(f'<tr><th class="s">{_e(k)}</th>{_cell(v)}</tr>' for k, v in headline.items())
        + "</tbody></table>",
    ]
    if notes:
        parts.append(f"<p>{_e(notes)}</p>")
    if series is not None:
        t, ys, windows, xlabel = series
        colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f"]
        legend = "".join(f'<span><i style="background:{colours[j % len(colours)]}"></i>{_e(n)}</span>' for j, n in enumerate(ys))
        parts += [
            "<h2>Time series</h2>",
            '<p class="hint">Wheel to zoom, drag to pan, double-click to reset. Shaded: fault windows.</p>',
            f'<div class="legend">{legend}</div><canvas id="ts" aria-label="time series"></canvas>',
            f'<script id="ts-data" type="application/json">{_series_json(t, ys, windows, xlabel)}</script>',
        ]
    for name, df in tables:
        parts.append(f"<h2>{_e(name)}</h2>")
        parts.append(table_html(df, name))
    if figures:
        parts.append("<h2>Figures</h2>")
        for f in figures:
            data = base64.b64encode(Path(f).read_bytes()).decode("ascii")
            parts.append(f'<figure><img alt="{_e(Path(f).name)}" src="data:image/png;base64,{data}"><figcaption>{_e(Path(f).name)}</figcaption></figure>')
    if scenario_text:
        parts += ["<h2>Scenario</h2>", f"<pre>{_e(scenario_text)}</pre>"]
    parts += [
        "<h2>Provenance</h2>",
        f"<p>Command: <code>{_e(command)}</code><br>Written {_e(now)}; "
        + ", ".join(f"{_e(k)} {_e(v)}" for k, v in versions.items())
        + "</p>",
        "</main>",
    ]
    if series is not None:
        parts.append(f"<script>{_JS}</script>")
    parts.append("</body></html>\n")
    path.write_text("".join(parts), encoding="utf-8")
    return path
