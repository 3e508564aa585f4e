"""The three HTML reports in a real headless Chromium, at 1280 px and at a true 390 px viewport.

report.html (the reproduction), the audit report of a run and calibration.html: each page
loads, ``window.innerWidth`` is the width asked for (the viewport, not only the window),
every image decodes, no key column of an audit table is clipped (in view without
scrolling at 1280 px; stacked inside the screen at 390 px), figure text is at least 9 CSS
px as shown, and the page never scrolls sideways. Screenshots of every page at both widths
go to ``build/screenshots/`` (gitignored) for a reviewer to open; the path is printed.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

BROWSER = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
SCREENSHOTS = Path(__file__).resolve().parents[2] / "build" / "screenshots"
WIDTHS = (390, 1280)

#: Measurements taken in the page once every image has decoded.
CHECK = """(async () => {
  const W = window.innerWidth;
  const imgs = [...document.images];
  await Promise.all(imgs.map(i => i.decode().catch(() => null)));
  const figText = imgs.filter(i => i.dataset.minFontPx).map(i => ({
      alt: i.alt.slice(0, 60), px: +i.dataset.minFontPx * i.getBoundingClientRect().width / i.naturalWidth}));
  const clipped = [];
  for (const cell of document.querySelectorAll('table.stack th.key, table.stack td.key')) {
    const r = cell.getBoundingClientRect();
    if (r.width === 0 && r.height === 0) continue;
    if (cell.tagName === 'TH' && r.bottom < -1000) continue;  // the header row moved away in the stacked layout
    const box = cell.closest('.scroll').getBoundingClientRect();
    if (r.right > Math.min(W, box.right) + 1 || r.left < -1) clipped.push(cell.dataset.label || cell.textContent);
  }
  return {
    innerWidth: W, height: document.documentElement.scrollHeight,
    images: imgs.length, undecoded: imgs.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.alt),
    figText: figText, clipped: clipped.slice(0, 10),
    pageFits: document.documentElement.scrollWidth <= W + 1,
    toc: document.querySelectorAll('nav.toc a').length,
    headings: [...document.querySelectorAll('h2')].map(h => h.textContent),
    headers: [...document.querySelectorAll('th')].map(th => th.textContent),
    hiddenCells: [...document.querySelectorAll('td')].filter(c => getComputedStyle(c).display === 'none'
                                                              || getComputedStyle(c).visibility === 'hidden').length,
    rawMarkdown: (document.body.innerText.match(/^- /mg) || []).length,
    warnings: document.querySelectorAll('.warn').length,
  };
})()"""


@pytest.fixture(scope="module")
def browser():
    pytest.importorskip("websockets", reason="the DevTools client needs websockets (the test extra)")
    from tests.report.cdp import Page

    page = Page(BROWSER)
    yield page
    page.close()


def check_page(browser, page: Path, width: int, name: str) -> dict:
    """Load ``page`` in an emulated ``width`` px viewport, measure it, write a full-page screenshot."""
    browser.open(page.as_uri(), width)
    check = browser.evaluate(CHECK)
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    check["screenshot"] = str(browser.screenshot(SCREENSHOTS / f"{name}-{width}.png", width, int(check["height"])))
    return check


def assert_readable(check: dict, width: int) -> None:
    assert check["innerWidth"] == width, f"the viewport is {check['innerWidth']} px, not {width}"
    assert check["images"] >= 1 and not check["undecoded"], check["undecoded"]
    assert not check["clipped"], f"key columns clipped at {width} px: {check['clipped']}"
    small = [f for f in check["figText"] if f["px"] < 9 - 0.05]
    assert not small, f"figure text under 9 CSS px at {width} px: {small}"
    assert check["pageFits"], "the page scrolls sideways; wide content must scroll in its own container"
    assert Path(check["screenshot"]).stat().st_size > 5000


pytestmark = [pytest.mark.skipif(BROWSER is None, reason="no chromium (make test installs Debian's package)"),
              pytest.mark.slow]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    from tests.conftest import cal_test_runs

    return cal_test_runs(tmp_path_factory.mktemp("browser-runs"), (3, 4), count=6, repeats=2)


@pytest.mark.parametrize("width", WIDTHS)
def test_audit_report_in_chromium(tmp_path, runs, browser, width):
    from probecommit.audit.pipeline import audit
    from probecommit.report.audit_report import write_html_report

    page = write_html_report(tmp_path / "audit.html", audit(runs["test"], resamples=200), title="Audit <b>x</b>")
    check = check_page(browser, page, width, "audit")
    assert_readable(check, width)
    assert check["hiddenCells"] == 0
    assert "episode coverage" in check["headers"] and not any("_" in h for h in check["headers"])
    assert "<b>x</b>" not in page.read_text()  # the title is escaped
    assert check["warnings"] >= 1  # 6 instances: fewer than 10 clusters is flagged
    assert check["figText"], "the audit figure carries its text size"


@pytest.mark.parametrize("width", WIDTHS)
def test_calibration_report_in_chromium(tmp_path, runs, browser, width):
    from probecommit.report.audit_report import write_html_report
    from probecommit.runner.calibration import calibrate

    res = calibrate(runs["cal"], runs["test"], alpha=0.2, resamples=200)
    page = write_html_report(tmp_path / "calibration.html", res.audit_calibrated, title="Calibration", calibration=res,
                             nominal=0.8)
    assert_readable(check_page(browser, page, width, "calibration"), width)


@pytest.mark.parametrize("width", WIDTHS)
def test_reproduction_report_in_chromium(tmp_path, browser, width):
    """report.html of the frozen publication, with a claims.json beside it and this branch's Fig. 2."""
    from probecommit.report.paper_html import write_paper_report
    from probecommit.report.pipeline_diagram import pipeline_figure

    repo = Path(__file__).resolve().parents[2]
    frozen = repo / "results" / "paper"
    if not (repo / "REPRODUCTION.md").is_file() or not frozen.is_dir():
        pytest.skip("no frozen publication in this checkout")
    pub = tmp_path / "paper"
    shutil.copytree(frozen, pub, ignore=shutil.ignore_patterns("*.parquet", "*.pdf", "report.html"))
    (pub / "figures").mkdir(exist_ok=True)
    pipeline_figure(pub / "figures" / "fig_2_pipeline.png")
    (pub / "claims.json").write_text(json.dumps({"counts": {"reproduced": 1, "differs": 1}, "claims": {
        "table-3": {"location": "Table III", "what": "audit <table>", "status": "reproduced", "paper": {"escape": 0.169},
                    "passed": 2, "total": 2},
        "fig-6": {"location": "Fig. 6", "what": "commit gates", "status": "differs", "paper": {"auc": 0.293}, "ours": 0.325}}}))
    page = write_paper_report(pub, repo / "REPRODUCTION.md", pub / "report.html")
    check = check_page(browser, page, width, "report")
    assert_readable(check, width)
    assert check["headings"][0] == "Summary" and check["toc"] >= 5  # the summary first
    assert check["rawMarkdown"] == 0, "Markdown list markers printed literally"
    assert "audit &lt;table&gt;" in page.read_text()


def test_screenshots_are_listed(capsys):
    """Say where the screenshots are (runs last in this module)."""
    shots = sorted(SCREENSHOTS.glob("*.png")) if SCREENSHOTS.is_dir() else []
    with capsys.disabled():
        print(f"\nbrowser screenshots ({len(shots)}): {SCREENSHOTS}")
