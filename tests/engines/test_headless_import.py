"""Physics imports MuJoCo without a GL back-end (no GLFW/cffi parsing) and leaves the environment as it was."""

import os
import subprocess
import sys

import pytest

pytest.importorskip("mujoco")

PROBE = """
import os, sys
from probecommit.engines import require
mj = require("mujoco")
mj.MjData(mj.MjModel.from_xml_string("<mujoco><worldbody><geom size='0.1'/></worldbody></mujoco>"))
print("glfw" in sys.modules, os.environ.get("MUJOCO_GL"))
"""


@pytest.mark.parametrize("gl", [None, "egl"])
def test_mujoco_is_imported_headless_unless_a_back_end_is_chosen(gl):
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    if gl:
        env["MUJOCO_GL"] = gl
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "None"] if gl is None else out[1] == gl  # the user's choice is kept
