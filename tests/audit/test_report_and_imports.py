"""The HTML report is self-contained; audit/ imports with no engine and no runner."""

import re
import subprocess
import sys

import numpy as np

from probecommit.audit.gates import gates_from_tables
from probecommit.audit.io import validate_episodes
from probecommit.audit.metrics import audit_table
from probecommit.report.audit_report import write_html_report
from probecommit.audit.synthetic import synthetic_episodes


def test_html_report_is_self_contained(tmp_path):
    df = validate_episodes(synthetic_episodes(12, 2, (1, 2, 3), n_particles=64))
    g = gates_from_tables(df, df.assign(predicted=np.clip(df["predicted"] + 0.1, 0, 1)))
    path = write_html_report(tmp_path / "r.html", audit_table(df, resamples=100), gates=g, title="t <&>")
    html = path.read_text()
    assert html.count("<img") == 2  # the audit figure and the gates figure (the audit one with a phone layout)
    assert not re.search(r"(src|href)=['\"](?!data:)", html)  # nothing fetched from outside
    assert "t &lt;&amp;&gt;" in html
    assert "cluster coverage" in html and "posterior variance" in html and "posterior_variance" not in html


BLOCKER = """
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        top = name.split('.')[0]
        if top in {'mujoco', 'pybullet', 'sapien', 'ray'} or name.startswith('probecommit.runner'):
            raise ImportError('blocked ' + name)
        return None
sys.meta_path.insert(0, Block())
import probecommit.audit
import probecommit.audit.io, probecommit.audit.metrics, probecommit.audit.stats, probecommit.audit.conformal
import probecommit.audit.margin, probecommit.audit.gates, probecommit.audit.surprise, probecommit.report.audit_report
import probecommit.audit.synthetic, probecommit.audit.pipeline
print('ok')
"""


def test_audit_imports_without_engines_or_runner():
    out = subprocess.run([sys.executable, "-c", BLOCKER], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
