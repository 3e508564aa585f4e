"""explain's steps set aside to processes of their own (issue 42): each runs in a fresh process, and its keys land
where running it in place would have put them, in submission order."""

from __future__ import annotations

import os

import pandas as pd
import pytest

from probecommit.studies.explain.background import Background
from probecommit.studies.explain.study import Explain, run_aside


def _fill_first(job: Explain) -> None:
    job.res["gru"].update(x=1.0)
    job.stored["first.parquet"] = pd.DataFrame({"v": [1, 2]})


def _fill_second(job: Explain) -> None:
    """Reads the rows the step before it stored (a step that reads another's rows goes aside with it)."""
    job.res["gru"].update(y=float(job.stored["first.parquet"]["v"].sum()))
    job.res["robust"].update(r=os.getpid())


def _fill_third(job: Explain) -> None:
    job.res["gru"].update(z=3.0)


def _fill_commits(job: Explain) -> None:
    job.commits["gates"] = [pd.DataFrame({"k": [1]})]


def _steps(job: Explain, aside: bool) -> list:
    def before() -> None:
        job.res["gru"].update(a=0.0)

    def after() -> None:
        job.res["gru"].update(b=9.0)

    if aside:
        return [before, job.aside(_fill_first, _fill_second), after, job.aside(_fill_third)]
    return [before, lambda: _fill_first(job), lambda: _fill_second(job), after, lambda: _fill_third(job)]


def test_steps_set_aside_put_their_keys_where_running_them_in_place_would(tmp_path):
    jobs = {}
    for aside in (True, False):
        job = jobs[aside] = Explain(tmp_path, True, lambda *a: None, 1, {})
        job.run_steps(_steps(job, aside))
    assert list(jobs[True].res["gru"]) == list(jobs[False].res["gru"]) == ["a", "x", "y", "b", "z"]
    assert jobs[True].res["gru"] == jobs[False].res["gru"]
    assert list(jobs[True].stored) == ["first.parquet"]
    if (os.cpu_count() or 1) > 1:  # in a process of its own
        assert jobs[True].res["robust"]["r"] != os.getpid()


@pytest.mark.parametrize("read", [lambda job: list(job.res["gru"].values()), lambda job: job.res["gru"].get("y"),
                                  lambda job: dict(job.res["gru"]), lambda job: "first.parquet" in job.stored,
                                  lambda job: job.stored.pop("first.parquet", None)])
def test_a_later_step_reading_what_a_step_set_aside_fills_is_refused(tmp_path, read):
    """Merged before or after it by timing, such a read would depend on the schedule (``lanes``)."""
    job = Explain(tmp_path, True, lambda *a: None, 1, {})
    with pytest.raises(RuntimeError, match=r"step 2 reads .* which .*_fill_first.* \(set aside at step 0\)"):
        job.run_steps([job.aside(_fill_first, _fill_second), lambda: job.res["gru"].update(b=1.0), lambda: read(job)])


def _answer() -> float:
    return 5.0


def test_what_a_submitted_job_hands_on_is_checked_as_a_job_set_aside(tmp_path):
    """``Explain.submit`` (a function and a hand-on, as the GRU and rig steps use) obeys the same rule."""
    job = Explain(tmp_path, True, lambda *a: None, 1, {})
    submit = lambda: job.submit(lambda v: job.res["gru"].update(w=v), _answer)  # noqa: E731
    with pytest.raises(RuntimeError, match=r"step 1 reads res gru 'w', which .*_answer"):
        job.run_steps([submit, lambda: job.res["gru"].get("w")])
    job = Explain(tmp_path, True, lambda *a: None, 1, {})
    job.run_steps([submit, lambda: job.res["gru"].get("other"), lambda: job.wait_aside(),
                   lambda: job.res["gru"]["w"]])
    assert job.res["gru"] == {"w": 5.0}


def test_a_step_may_read_what_a_job_aside_fills_once_it_waited_for_it(tmp_path):
    job = Explain(tmp_path, True, lambda *a: None, 1, {})
    got: list = []
    job.run_steps([job.aside(_fill_first), lambda: (job.wait_aside(), got.append(job.res["gru"]["x"])),
                   lambda: got.append(job.stored["first.parquet"]["v"].sum())])
    assert got == [1.0, 3]


def test_reads_before_the_step_is_set_aside_and_of_other_keys_pass(tmp_path):
    job = Explain(tmp_path, True, lambda *a: None, 1, {})
    job.run_steps([lambda: job.res["gru"].update(a=0.0), lambda: job.res["gru"].get("x"),
                   job.aside(_fill_first), lambda: job.res["gru"]["a"], lambda: job.res["robust"].get("r")])
    assert job.res["gru"] == {"a": 0.0, "x": 1.0}


def test_a_step_that_fills_rows_kept_in_step_order_is_refused_aside(tmp_path):
    with pytest.raises(RuntimeError, match="run it in place"):
        run_aside(tmp_path, True, 1, {}, (_fill_commits,))


def test_background_runs_each_function_in_a_fresh_process_and_finishes_up_to_one():
    got: list = []
    work = Background()
    try:
        first = work.submit(got.append, os.getpid)
        work.submit(got.append, os.getpid)
        work.finish(until=first)
        assert len(got) == 1  # only up to that one
        work.finish()
    finally:
        work.close()
    if (os.cpu_count() or 1) > 1:
        assert len(set(got)) == 2 and os.getpid() not in got


def test_a_step_set_aside_waits_for_the_late_needs_it_reads_only(tmp_path, monkeypatch):
    job = Explain(tmp_path, True, lambda *a: None, 1, {}, ready=lambda names=None: waited.append(names))
    waited: list = []
    monkeypatch.setattr(job.background, "submit", lambda then, fn, *args: args[-1])
    assert job.aside(_fill_first, needs=())() == (_fill_first,)
    job.aside(_fill_first, needs=("breadth",))()
    job.aside(_fill_first)()
    assert waited == [("breadth",), None]  # needs=(): none; default: every late need


def _rows() -> pd.DataFrame:
    return pd.DataFrame({"v": [1, 2, 3]})


def test_a_hand_on_reading_what_it_wrote_is_the_jobs_read_not_a_steps(tmp_path, monkeypatch):
    """On one CPU a hand-on runs at once, inside the step that submitted it: its reads are the job's own."""
    monkeypatch.setattr(os, "cpu_count", lambda: 1)

    def then(rows: pd.DataFrame) -> None:
        job.stored["x.parquet"] = rows
        job.res["gru"].update(n=len(job.stored["x.parquet"]))

    job = Explain(tmp_path, True, lambda *a: None, 1, {})
    job.run_steps([lambda: job.submit(then, _rows), lambda: job.res["robust"].get("r")])
    assert job.res["gru"] == {"n": 3}
