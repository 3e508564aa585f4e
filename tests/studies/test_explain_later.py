"""explain's deferred step (side by side it waits for the engines study): its keys land where they would in place."""

from probecommit.studies.explain.lanes import Reads
from probecommit.studies.explain.study import Explain


def _job(ready=None) -> Explain:
    job = Explain.__new__(Explain)  # only the results, the wait and the read log are used
    job.res, job.ready, job.reads = {"missing": {}}, ready, Reads()
    return job


def _steps(job: Explain) -> list:
    def first():
        job.res["missing"].update(a=1, b=2)

    def deferred():
        job.res["missing"].update(p=10, q=11)

    def middle():
        job.res["missing"].update(c=3)

    place, later = job._later("missing", deferred, ("engines",))
    return [first, place, middle, later], [first, deferred, middle]


def test_a_deferred_step_puts_its_keys_where_running_it_in_place_would():
    waited = []
    job = _job(lambda names=None: waited.append(names))
    deferred_order, in_place = _steps(job)
    for step in deferred_order:
        step()
    reference = _job()
    for step in _steps(reference)[1]:
        step()
    assert list(job.res["missing"].items()) == list(reference.res["missing"].items()) == [
        ("a", 1), ("b", 2), ("p", 10), ("q", 11), ("c", 3)]
    assert waited == [("engines",)]
