"""``report.html`` in a real headless browser (Debian's chromium driven by Selenium): the page
loads without console errors, every figure and the interactive panel render with a non-zero
size, the zoom works, the page makes no external request, and the numbers in its tables are
those of the CSV files beside it.

CI installs ``chromium`` and ``chromium-driver`` and sets ``NAVFDI_REQUIRE_BROWSER=1`` so that a
missing browser fails the run instead of skipping these tests.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import warnings
from pathlib import Path

import pandas as pd
import pytest

import navfdi

DATA = Path(__file__).parent / "data" / "rinex"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver")


@pytest.fixture(scope="module")
def browser():
    if not (CHROMIUM and DRIVER):
        if os.environ.get("NAVFDI_REQUIRE_BROWSER"):
            pytest.fail("chromium and chromedriver are required (apt-get install chromium chromium-driver)")
        pytest.skip("no chromium/chromedriver on this machine (CI installs them)")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1280,1800"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    drv = webdriver.Chrome(service=Service(DRIVER), options=opts)
    drv.set_page_load_timeout(60)
    yield drv
    drv.quit()


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    d = tmp_path_factory.mktemp("reports")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        navfdi.run_scenario("yang2013", seed=1).write(d / "run")
        navfdi.run_scenario("shao2018", seed=1).write(d / "tight")
        navfdi.montecarlo("yang2013", runs=4, seed=0, progress=False).write(d / "mc")
        navfdi.gnss_solve(DATA / "rover.obs.gz", DATA / "base.nav", faults=["G13:step:20m:100s:200s"], truth=navfdi.gnss.read_truth_file(DATA / "rover_position.txt")).write(d / "gnss")
    return d


def _load(browser, path: Path) -> list[dict]:
    browser.get(path.resolve().as_uri())
    browser.execute_script("return document.readyState")
    return [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]


def _table(browser, name: str) -> list[list[str | None]]:
    return browser.execute_script(
        """
        const t = document.querySelector(`table[data-table="${arguments[0]}"]`);
        if (!t) return null;
        return Array.from(t.querySelectorAll('tbody tr')).map(r => Array.from(r.cells).map(c => c.dataset.value === undefined ? c.textContent : c.dataset.value));
        """,
        name,
    )


def _same(page: str | None, csv) -> bool:
    if isinstance(csv, float) and math.isnan(csv):
        return page in ("nan", "")
    if isinstance(csv, (int, float)) and not isinstance(csv, bool):
        return page is not None and page != "" and float(page) == float(csv)
    return str(page) == ("" if csv is None or (isinstance(csv, float) and math.isnan(csv)) else str(csv))


@pytest.mark.parametrize("which,csv", [("run", "errors.csv"), ("run", "events.csv"), ("tight", "satellites.csv"), ("mc", "summary.csv"), ("gnss", None)])
def test_report_renders_and_its_numbers_are_the_csv_numbers(browser, reports, which, csv):
    page = reports / which / "report.html"
    errors = _load(browser, page)
    assert not errors, errors
    sizes = browser.execute_script("return Array.from(document.images).map(i => [i.naturalWidth, i.clientWidth, i.clientHeight, i.complete])")
    assert sizes and all(w > 0 and cw > 0 and ch > 0 and ok for w, cw, ch, ok in sizes), sizes
    if csv is None:
        return
    rows = _table(browser, csv)
    df = pd.read_csv(reports / which / csv)
    assert rows is not None and len(rows) == len(df)
    for r, (_, want) in zip(rows, df.iterrows()):
        assert len(r) == len(want)
        for got, (col, v) in zip(r, want.items()):
            assert _same(got, v), (csv, col, got, v)


def test_the_time_series_panel_draws_and_zooms(browser, reports):
    errors = _load(browser, reports / "run" / "report.html")
    assert not errors, errors
    w, h = browser.execute_script("const c = document.getElementById('ts'); return [c.clientWidth, c.clientHeight]")
    assert w > 0 and h > 0
    # Something was drawn: the canvas is not blank.
    painted = browser.execute_script(
        "const c = document.getElementById('ts'); const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;"
        "let n = 0; for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++; return n"
    )
    assert painted > 1000
    assert browser.execute_script("return window.navfdiZoom(300, 500)") == [300, 500]
    assert not [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]


def test_reports_make_no_external_request(reports):
    for page in reports.glob("*/report.html"):
        text = page.read_text()
        assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text), page
        assert "@import" not in text and "url(http" not in text
        assert text.count("data:image/png;base64,") == len(list(page.parent.glob("*.png")))
