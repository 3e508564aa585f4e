"""`--workers N` on a thread-safe simulator runs N threads and says why (issue 42, target 5)."""

from probecommit.runner import build, study
from tests.conftest import small_config


def test_workers_on_a_thread_safe_simulator_become_threads_with_a_reason():
    config = small_config()  # analytic: thread-safe
    workers, threads, why = study.choose_backend(config, 2)
    assert (workers, threads) == (1, 2)
    assert why.startswith("--workers 2: running the units in 2 threads") and "analytic" in why


def test_explicit_threads_ray_one_worker_or_an_unsafe_simulator_keep_the_choice(monkeypatch):
    config = small_config()
    assert study.choose_backend(config, 2, threads=1) == (2, 1, None)  # --workers 2 --threads 1: processes
    assert study.choose_backend(config, 2, ray="local") == (2, None, None)
    assert study.choose_backend(config, 1) == (1, None, None)

    class Unsafe:
        thread_safe = False

    monkeypatch.setattr(build, "simulator_class", lambda cfg: Unsafe)
    assert study.choose_backend(config, 2) == (2, None, None)
