"""A command's end without the interpreter's teardown (``process.finish``) keeps every effect of
interpreter exit: threads joined, pools finished, atexit handlers run, output flushed, the status."""

import subprocess
import sys
import textwrap

import pytest

from probecommit.process.finish import exit_status

PROGRAM = textwrap.dedent("""
    import atexit, sys, threading, time
    from concurrent.futures import ThreadPoolExecutor
    from pathlib import Path
    from probecommit.process.finish import exit_process

    out = Path(sys.argv[1])
    atexit.register(lambda: (out / "atexit").write_text("ran"))
    def late():
        time.sleep(0.2)
        (out / "thread").write_text("joined")
    threading.Thread(target=late).start()  # a non-daemon thread still running
    pool = ThreadPoolExecutor(1)
    pool.submit(lambda: (time.sleep(0.2), (out / "pool").write_text("done")))  # a pool's pending work
    sys.stdout.write("x" * 100000 + "END")  # buffered output (a pipe)
    exit_process({code})
""")


@pytest.mark.parametrize("code, status", [(None, 0), (0, 0), (3, 3), ("a message", 1)])
def test_the_process_ends_with_every_effect_of_interpreter_exit_and_its_status(tmp_path, code, status):
    done = subprocess.run([sys.executable, "-c", PROGRAM.format(code=repr(code)), str(tmp_path)],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == status, done.stderr
    assert done.stdout.endswith("END") and len(done.stdout) == 100003
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == {"atexit": "ran", "thread": "joined", "pool": "done"}
    if isinstance(code, str):
        assert done.stderr.strip() == code


def test_exit_status_is_what_sys_exit_gives(capsys):
    assert [exit_status(None), exit_status(0), exit_status(7)] == [0, 0, 7]
    assert exit_status("why") == 1
    assert capsys.readouterr().err == "why\n"
