"""The HTML audit report in a real headless browser (Chromium from the system packages).

At phone width (390 px) and laptop width (1280 px): the page loads, every embedded
figure decodes, no table cell is hidden, and the page itself never scrolls sideways
(wide tables scroll inside their own container).
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import pytest

from probecommit.audit.pipeline import audit
from probecommit.report.audit_report import write_html_report
from probecommit.runner.study import run_study
from tests.conftest import small_config

BROWSER = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")

CHECK = """<script>
window.addEventListener('load', () => {
  const imgs = [...document.images];
  const cells = [...document.querySelectorAll('th, td')];
  document.body.setAttribute('data-check', JSON.stringify({
    images: imgs.length,
    decoded: imgs.every(i => i.complete && i.naturalWidth > 0),
    hidden: cells.filter(c => getComputedStyle(c).display === 'none' || getComputedStyle(c).visibility === 'hidden').length,
    headers: [...document.querySelectorAll('th')].map(th => th.textContent),
    pageFits: document.documentElement.scrollWidth <= window.innerWidth + 1,
    warnings: document.querySelectorAll('.warn').length,
  }));
});
</script>"""


@pytest.mark.skipif(BROWSER is None, reason="no chromium (make test installs the Debian package)")
@pytest.mark.parametrize("width,height", [(390, 844), (1280, 800)])
def test_report_renders_readably_in_a_real_browser(tmp_path, width, height):
    run = run_study(small_config(name="browser", instances={"count": 6}), tmp_path / "run").run_dir
    report = write_html_report(tmp_path / "audit.html", audit(run, resamples=200), title="Audit <b>x</b>")
    page = tmp_path / "checked.html"
    page.write_text(report.read_text().replace("</body>", CHECK + "</body>"))
    out = subprocess.run([BROWSER, "--headless", "--no-sandbox", "--disable-gpu", f"--window-size={width},{height}",
                          "--virtual-time-budget=5000", "--dump-dom", page.as_uri()],
                         capture_output=True, text=True, timeout=120)
    found = re.search(r"data-check=\"([^\"]*)\"", out.stdout)
    assert found, out.stderr[-2000:]
    check = json.loads(found.group(1).replace("&quot;", '"'))
    assert check["images"] >= 1 and check["decoded"]
    assert check["hidden"] == 0
    assert check["pageFits"], "the page scrolls sideways; wide tables must scroll in their own container"
    assert "episode coverage" in check["headers"] and not any("_" in h for h in check["headers"])
    assert check["warnings"] >= 1  # 6 instances: the few-clusters warning is shown
    assert "<b>x</b>" not in report.read_text()  # the title is escaped
