"""Turn a study config into a run directory: units, backends, resume.

A *unit* is a fixed group of ``unit_instances`` instances with all their repeats.
Units are independent (every random draw is keyed by instance and repeat), so they
run in any order, in local processes or on Ray, and a killed run resumes by
skipping the units already committed in a batch on disk. Results are bit-identical
whatever the backend or the number of workers.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import logging
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator

import numpy as np

from probecommit.runner import build
from probecommit.runner.config import StudyConfig, dump_config, parse_config
from probecommit.runner.inference import (
    build_trace,
    commit,
    failed_episode_columns,
    instance_arrays,
    rollout,
    rollout_adaptive,
)
from probecommit.runner.instances import InstanceTable, instance_table
from probecommit.store.rundir import RunDir, arrow_from_columns, arrow_table
from probecommit.store.schema import EPISODE_COLUMNS, INSTANCE_COLUMNS, PROBE_COLUMNS, cache_columns
from probecommit.errors import UnavailableError, UsageError

if TYPE_CHECKING:  # pandas is imported where a DataFrame is built: a run's own path needs none
    import pandas as pd

logger = logging.getLogger(__name__)


@dataclass
class StudyResult:
    """A run's directory, manifest and final episodes table. ``episodes_table`` is the Arrow table (what
    the command's own summary reads); ``episodes``, the DataFrame, is converted on first use, since the
    conversion imports pandas, which a run does not otherwise need (docs/decisions.md, "run: ...")."""

    run_dir: Path
    manifest: dict[str, Any]
    episodes_table: Any = field(repr=False)

    @functools.cached_property
    def episodes(self) -> pd.DataFrame:
        """The final episodes table as ``pd.read_parquet`` of its file gives it."""
        return self.episodes_table.to_pandas()

    @property
    def failed_episodes(self) -> int:
        """Episode rows marked failed (engine NaN or error), rollout rows included."""
        if "status" not in self.episodes_table.column_names:
            return 0
        return sum(status != "ok" for status in self.episodes_table.column("status").to_pylist())

    @property
    def belief_reset_rows(self) -> int:
        """Episode rows whose belief lost every particle (``belief_resets`` > 0)."""
        from probecommit.store.arrow_columns import to_numpy

        if "belief_resets" not in self.episodes_table.column_names:
            return 0
        resets = to_numpy(self.episodes_table.column("belief_resets")).astype(float)  # a column of nulls: NaN
        return int(np.sum(np.nan_to_num(resets) > 0))


def unit_names(n_instances: int, unit_instances: int) -> list[tuple[str, slice]]:
    return [
        (f"unit-{i // unit_instances:05d}", slice(i, min(i + unit_instances, n_instances)))
        for i in range(0, n_instances, unit_instances)
    ]


@dataclass(frozen=True, eq=False)
class RunParts:
    """What a run builds once from its validated config and hands down to every unit: the
    config, the model, the particle filter and the executors.

    None of them changes while episodes are computed, so the units of one process (serial or
    threads) share one instance. A simulator is not a part: each unit builds its own, which
    counts that unit's engine calls and holds its answers. Sent to a worker process or a Ray
    task, a ``RunParts`` travels as the config's data (:meth:`__reduce__`) and is rebuilt there
    once per process (:func:`_parts_of_data`), not once per unit.

    ``simulator``: a factory of each unit's simulator where the config's engine is not the scene (an experiment
    whose commit is another push than the family's, run in its own process; None: the config's engine).
    """

    config: StudyConfig
    model: Any
    pfilter: Any
    executors: list
    simulator: Any = None

    @classmethod
    def build(cls, config: StudyConfig) -> "RunParts":
        """Model, filter and executors of a validated config (built here, once)."""
        model = build.build_model(config)
        return cls(config, model, build.build_filter(model, config.belief), build.config_executors(config, model))

    def __reduce__(self) -> tuple:
        # The built model, filter and executors stay in their process; the config travels as data.
        return _parts_of_data, (json.dumps(self.config.model_dump(mode="json"), sort_keys=True),)


@functools.lru_cache(maxsize=4)
def _parts_of_data(config_json: str) -> RunParts:
    """The parts of a config's data, validated and built once per process (a worker process or
    a Ray worker receives the same data with every group of units it computes)."""
    return RunParts.build(parse_config(json.loads(config_json)))


def _parts(given: "RunParts | dict") -> RunParts:
    """``given`` itself, or the (per-process) parts of config data (a caller holding only the data)."""
    return given if isinstance(given, RunParts) else _parts_of_data(json.dumps(given, sort_keys=True))


def compute_unit(parts: "RunParts | dict", instances: "InstanceTable | pd.DataFrame", unit: str) -> tuple[str, dict[str, Any], dict[str, Any]]:
    """Run one unit end to end in memory; returns ``(unit, tables, stats)``, the tables as
    the Arrow tables the run stores (converted here, in the worker, so the driver that
    writes them converts nothing).

    Top-level, argument-only and free of disk writes, so process pools and Ray
    workers (on any node, with no shared filesystem) can run it; only the driver
    writes the run directory.
    """
    start = time.perf_counter()
    parts, instances = _parts(parts), InstanceTable.of(instances)
    model = parts.model
    batch, columns, simulator = _episodes(parts, instances)
    n_rows = len(next(iter(columns.values()))) if columns else 0
    if np.any(batch.status != "ok"):  # rare: through pandas, as the rows were always joined
        import pandas as pd

        failed = pd.DataFrame(failed_episode_columns(batch, model.variant))
        frame = pd.concat([pd.DataFrame(columns), failed], ignore_index=True) if columns else failed
        episodes = arrow_table(frame, EPISODE_COLUMNS)
        failed_rows = int((frame["status"] != "ok").sum())
    else:
        episodes = arrow_from_columns(columns, n_rows, EPISODE_COLUMNS)
        failed_rows = int(np.sum(columns["status"] != "ok")) if columns else 0
    stats = {
        "unit": unit,
        "engine_calls": dict(simulator.engine_calls),
        "engine_s": simulator.engine_seconds,
        "wall_s": time.perf_counter() - start,
        "pid": os.getpid(),
        "episodes": int(batch.n_episodes),
        "failed_trajectories": int(np.sum(batch.status != "ok")),
        "failed_rows": failed_rows,
    }
    probes = batch.probes_columns()
    cache = cache_columns(simulator.cache_records(), model.latent_names)
    tables = {
        "instances": arrow_from_columns(instances.columns, len(instances), INSTANCE_COLUMNS),
        "probes": arrow_from_columns(probes, len(probes["instance_id"]), PROBE_COLUMNS),
        "engine_cache": arrow_from_columns(cache, len(cache["engine"])),
        "episodes": episodes,
    }
    return unit, tables, stats


#: Episodes computed in one batch when several small units go together (:func:`compute_units`),
#: at 1024 particles (fewer at more particles: a group holds no more belief memory than 256
#: episodes of 1024 particles, and a unit larger than that is computed alone, as before);
#: ``$PROBECOMMIT_GROUP_EPISODES`` overrides it (1: every unit alone).
GROUP_EPISODES = int(os.environ.get("PROBECOMMIT_GROUP_EPISODES", "256"))
GROUP_PARTICLES = 1024


def compute_units(parts: "RunParts | dict", instances: "InstanceTable | pd.DataFrame", units: list[tuple[str, int]]) -> list[tuple]:
    """Several units computed as one batch of episodes and returned unit by unit: the
    ``(unit, tables, stats)`` of :func:`compute_unit` for each, with identical tables.

    A unit of a few episodes spends most of its time on per-call overheads (a filter update
    of 16 episodes costs nearly what one of 256 costs), so consecutive small units are
    computed together and split afterwards; the unit stays the grain of resumption. Exact
    because an episode never depends on its batch (``tests/runner/test_batch_independence.py``),
    rows come in instance order (each unit's rows a contiguous slice) and, with every truth
    distinct, each engine answer belongs to one unit. Otherwise (a truth shared by two
    instances, or a failed rollout) the units are computed one by one. The group's engine
    calls and times are recorded on its first unit (the run's manifest sums them).

    Args:
        parts: The run's :class:`RunParts` (or its config's JSON data: then built once per process).
        instances: The units' instances, in unit order.
        units: ``(name, number of instances)`` of each unit, in order.
    """
    parts, instances = _parts(parts), InstanceTable.of(instances)
    one_by_one = functools.partial(_units_one_by_one, parts, instances, units)
    if len(units) == 1:
        return one_by_one()
    start = time.perf_counter()
    owner = _truth_owners(instance_arrays(instances, parts.model)[0], units)
    if owner is None:  # a truth shared by two instances: whose engine answer is it?
        return one_by_one()
    batch, columns, simulator = _episodes(parts, instances)
    if np.any(batch.status != "ok"):  # failed rollouts: their rows are joined unit by unit
        return one_by_one()
    by_unit: list[list[dict]] = [[] for _ in units]
    for record in simulator.cache_records():
        u = owner.get(tuple(record["theta"]))
        if u is None:  # an answer keyed otherwise than by an instance's truth: no owner to give it
            return one_by_one()
        by_unit[u].append(record)
    return _split_group(parts, instances, units, batch, columns, simulator, by_unit, start)


def _truth_owners(truths: np.ndarray, units: list[tuple[str, int]]) -> dict[tuple[float, ...], int] | None:
    """Each instance truth's unit (the units in order, ``n`` instances each), or None when two
    instances share a truth: an engine answer is keyed by the truth, so it would have two owners."""
    owner: dict[tuple[float, ...], int] = {}
    at = 0
    for u, (_, n) in enumerate(units):
        for theta in truths[at:at + n]:
            owner.setdefault(tuple(theta.astype(float).tolist()), u)
        at += n
    return owner if len(owner) == len(truths) else None


def _split_group(parts: RunParts, instances: InstanceTable, units: list[tuple[str, int]], batch: Any,
                 columns: dict[str, Any], simulator: Any, by_unit: list[list[dict]], start: float) -> list[tuple]:
    """A group's results cut into its units' ``(unit, tables, stats)``.

    Each table is built once for the group and sliced per unit (a slice shares the group's
    buffers; its types and pandas metadata are those a unit's own table gets: tested on the
    final tables). The group's engine calls and times go on its first unit.
    """
    n_rows = len(next(iter(columns.values()))) if columns else 0
    per_episode = n_rows // max(batch.n_episodes, 1)
    budget = batch.u.shape[1]
    probes = batch.probes_columns()
    whole = {"instances": arrow_from_columns(instances.columns, len(instances), INSTANCE_COLUMNS),
             "probes": arrow_from_columns(probes, batch.n_episodes * budget, PROBE_COLUMNS),
             "episodes": arrow_from_columns(columns, n_rows, EPISODE_COLUMNS)}
    out, first_episode, first_instance = [], 0, 0
    for u, (name, n) in enumerate(units):
        episodes = n * parts.config.repeats
        rows = slice(first_episode * per_episode, (first_episode + episodes) * per_episode)
        taps = slice(first_episode * budget, (first_episode + episodes) * budget)
        unit_columns = {"status": columns["status"][rows]} if columns else {}
        cache = cache_columns(by_unit[u], parts.model.latent_names)
        lead = u == 0
        stats = {
            "unit": name,
            "engine_calls": dict(simulator.engine_calls) if lead else {},
            "engine_s": simulator.engine_seconds if lead else 0.0,
            "wall_s": time.perf_counter() - start if lead else 0.0,
            "pid": os.getpid(),
            "episodes": episodes,
            "failed_trajectories": 0,
            "failed_rows": int(np.sum(unit_columns["status"] != "ok")) if unit_columns else 0,
            "group": [unit for unit, _ in units] if lead else units[0][0],
        }
        tables = {
            "instances": whole["instances"].slice(first_instance, n),
            "probes": whole["probes"].slice(taps.start, taps.stop - taps.start),
            "engine_cache": arrow_from_columns(cache, len(cache["engine"])),
            "episodes": whole["episodes"].slice(rows.start, rows.stop - rows.start),
        }
        out.append((name, tables, stats))
        first_episode += episodes
        first_instance += n
    return out


def _units_one_by_one(parts: RunParts, instances: InstanceTable, units: list[tuple[str, int]]) -> list[tuple]:
    out, at = [], 0
    for name, n in units:
        out.append(compute_unit(parts, instances.rows(slice(at, at + n)), name))
        at += n
    return out


def _episodes(parts: RunParts, instances: InstanceTable) -> tuple[Any, dict[str, Any], Any]:
    """Rollouts, beliefs and commits of ``instances``: the probe batch, the episode table's
    columns (``commit(..., as_columns=True)``; empty when every rollout failed) and the simulator
    (built here: one per unit or group, as it counts their engine calls)."""
    config, model, pfilter = parts.config, parts.model, parts.pfilter
    simulator = build.build_simulator(config) if parts.simulator is None else parts.simulator()
    schedule = config.probes.schedule
    if schedule == "adaptive":
        batch = rollout_adaptive(instances, config.repeats, config.probes.budget, model, pfilter, simulator, config.seed)
    else:
        batch = rollout(instances, config.repeats, schedule, config.probes.budget, model, simulator, config.seed)
    if config.simulator.execute_all_aims:
        truths, contexts = instance_arrays(instances, model)
        for theta, ctx in zip(truths, contexts):
            for aim in model.action_grid:
                try:
                    simulator.execute(theta, aim, ctx if len(ctx) else None)
                except Exception:  # noqa: BLE001 - recorded when an episode commits there
                    pass
    columns: dict[str, Any] = {}
    if np.any(batch.status == "ok"):  # a unit whose every trajectory failed has nothing to infer
        trace = build_trace(pfilter, batch, config.seed, config.probes.commit_budgets, keep_weights=True)
        columns = commit(trace, model, simulator, parts.executors, thresholds=config.belief.nu,
                         as_columns=True)
    return batch, columns, simulator


Job = tuple[RunParts, InstanceTable, list[tuple[str, int]]]
Result = list[tuple[str, dict[str, Any], dict[str, Any]]]


def _run_serial(jobs: list[Job]) -> Iterator[Result]:
    for job in jobs:
        yield compute_units(*job)


def _run_threads(jobs: list[Job], threads: int) -> Iterator[Result]:
    """Units in ``threads`` threads of this process, yielded as they finish.

    For thread-safe simulators only (``CachedSimulator.thread_safe``): the compiled kernels
    and NumPy's array operations release the GIL, so two units use two cores without a
    second interpreter's imports. At most ``2 * threads`` units are in memory at once.
    """
    from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

    queue = iter(jobs)
    with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="probecommit-unit") as pool:
        pending = {pool.submit(compute_units, *job) for job in itertools.islice(queue, 2 * threads)}
        try:
            while pending:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                pending |= {pool.submit(compute_units, *job) for job in itertools.islice(queue, len(done))}
                for fut in done:
                    yield fut.result()
        finally:
            for fut in pending:
                fut.cancel()


def unit_threads(config: StudyConfig, threads: int | None = None) -> int:
    """Threads for a study's units in this process: ``threads``, else :func:`tasks.base.engine_threads`
    (``$PROBECOMMIT_ENGINE_THREADS`` or the CPUs, at most 4); 1 unless the study's simulator is
    ``thread_safe``."""
    from probecommit.tasks.base import engine_threads

    wanted = engine_threads() if threads is None else int(threads)
    if wanted < 1:
        raise UsageError(f"threads must be >= 1, got {threads!r}")
    if wanted == 1 or not build.simulator_class(config).thread_safe:
        return 1
    return wanted


def choose_backend(config: StudyConfig, workers: int, ray: str | None = None,
                   threads: int | None = None) -> tuple[int, int | None, str | None]:
    """What ``--workers`` runs as: ``(workers, threads, why)``, ``why`` a line for the user when it differs.

    Worker processes each start an interpreter, import the package and build the model and
    kernels again (seconds, and hundreds of MB each), and on a machine whose CPUs the
    threads of one process already fill they only add that cost: ``--workers 2`` measured
    0.72x one worker on 2 cores. So when the study's simulator is thread-safe, ``--workers N``
    runs the units in N threads of this process (the same tables: results never depend on
    the backend) and says why. ``--threads`` or ``--ray`` given (``--workers 2 --threads 1``:
    processes), or a simulator that is not thread-safe, keep the processes.
    """
    if workers <= 1 or ray is not None or threads is not None or not build.simulator_class(config).thread_safe:
        return workers, threads, None
    return 1, workers, (f"--workers {workers}: running the units in {workers} threads of this process instead of "
                        f"{workers} worker processes: the {config.simulator.engine} simulator is thread-safe, and threads "
                        "share one interpreter, its imports, model and compiled kernels (each process would load its own). "
                        "Same results. (--threads 1 keeps the worker processes.)")


def _init_worker(parent_pid: int, poll_s: float = 0.5, engine_threads: int | None = None) -> None:
    """Pool-worker initializer: exit as soon as the parent is gone (even after SIGKILL).

    A killed parent cannot clean up its pool; each worker watches its parent pid from a
    daemon thread and leaves when it changes (the worker was re-parented). With
    ``engine_threads``, the worker's engine threads (``tasks.base.engine_threads``) unless
    the user set them: the workers share the CPUs.
    """
    import threading

    from probecommit.tasks.base import ENGINE_THREADS_ENV

    if engine_threads is not None:
        os.environ.setdefault(ENGINE_THREADS_ENV, str(engine_threads))

    def watch() -> None:
        while True:
            time.sleep(poll_s)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="die-with-parent", daemon=True).start()


def _run_processes(jobs: list[Job], workers: int) -> Iterator[Result]:
    import multiprocessing as mp
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    # "spawn": engines (MuJoCo, PyBullet, SAPIEN) hold native state that must not be
    # forked, and a spawned worker starts from the same imports on every platform.
    from probecommit.tasks.base import engine_threads

    n_workers = min(workers, len(jobs))
    threads = max(1, engine_threads() // n_workers)  # the processes share the CPUs the threads would use
    with ProcessPoolExecutor(max_workers=n_workers, mp_context=mp.get_context("spawn"),
                             initializer=_init_worker, initargs=(os.getpid(), 0.5, threads)) as pool:
        pending = {pool.submit(compute_units, *job) for job in jobs}
        try:
            while pending:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    yield fut.result()
        finally:
            for fut in pending:
                fut.cancel()


def package_runtime_env() -> dict[str, Any]:
    """Ray runtime environment that ships this probecommit to every worker.

    Workers of a real cluster need not have probecommit installed: Ray uploads the package
    folder once (``py_modules``) and puts it first on the workers' import path, so they
    run exactly the driver's code.
    """
    package = Path(__file__).resolve().parents[1]
    return {"py_modules": [str(package)], "excludes": ["__pycache__", "*.pyc"]}


#: Seconds ``--ray local`` may take to start its instance, and ``--ray ADDRESS`` to connect.
RAY_START_TIMEOUT_S = float(os.environ.get("PROBECOMMIT_RAY_TIMEOUT_S", "60"))
#: Seconds a ``--ray host:port`` has to accept a connection and answer as a gRPC (HTTP/2) server.
RAY_PROBE_TIMEOUT_S = 3.0


def ray_init_kwargs(address: str, workers: int) -> dict[str, Any]:
    """``ray.init`` arguments for ``--ray``: ``local`` always starts an instance of its own
    (``address="local"``: never one another process recorded), else connect and ship the package."""
    common = dict(include_dashboard=False, log_to_driver=False, configure_logging=False)
    if address == "local":
        return dict(address="local", num_cpus=workers if workers > 1 else None, **common)
    return dict(address=address, runtime_env=package_runtime_env(), **common)


#: The HTTP/2 client preface and an empty SETTINGS frame: what a gRPC client (Ray's) sends first.
_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + b"\x00\x00\x00\x04\x00\x00\x00\x00\x00"


def check_reachable(address: str, timeout_s: float = RAY_PROBE_TIMEOUT_S) -> None:
    """Fail within seconds when no Ray head listens at ``host:port`` (Ray itself retries for minutes).

    A TCP connection is not enough: a port that accepts but is not Ray (a web server, a
    silent socket) made ``ray.init`` hang for minutes. Ray's head is a gRPC server, so it
    must answer the HTTP/2 preface with a SETTINGS frame within ``timeout_s``.

    Raises:
        RuntimeError: one line naming the address.
    """
    import socket

    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        raise UnavailableError(f"--ray expects 'local', 'auto' or host:port, got {address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout_s) as conn:
            conn.settimeout(timeout_s)
            conn.sendall(_HTTP2_PREFACE)
            answer = b""
            while len(answer) < 9:  # a frame header: length (3), type (1), flags (1), stream (4)
                more = conn.recv(9 - len(answer))
                if not more:
                    break
                answer += more
    except socket.timeout:
        raise UnavailableError(f"{address} accepted a connection but did not answer as a Ray head (no gRPC reply within "
                           f"{timeout_s:g} s); check the address (the head's GCS port, 6379 by default)") from None
    except OSError as exc:
        raise UnavailableError(f"cannot reach the Ray cluster at {address}: {exc.strerror or exc}") from None
    if len(answer) < 9 or answer[3] != 0x4:
        raise UnavailableError(f"{address} is not a Ray head (it did not answer as a gRPC server); check the address "
                           "(the head's GCS port, 6379 by default)")


class _RayStartExpired(BaseException):
    """Raised in the main thread by the alarm of :func:`_init_within` (a BaseException, so no
    ``except Exception`` inside Ray swallows it)."""


def _init_within(ray: Any, kwargs: dict[str, Any], address: str, timeout_s: float) -> None:
    """``ray.init(**kwargs)``, given up after ``timeout_s`` with one line (it has no timeout of its own).

    Ray must start in the thread that keeps running: the processes it starts die with the
    thread that started them (Linux's parent-death signal is per thread), so a helper thread
    would kill the instance when it ends. The timeout is an interval timer whose signal raises
    in the main thread; called from another thread, Ray starts without one.
    """
    import signal
    import threading

    def expired(signum, frame):  # noqa: ARG001 - a signal handler's signature
        raise _RayStartExpired

    timed = threading.current_thread() is threading.main_thread() and hasattr(signal, "setitimer")
    if timed:
        previous = signal.signal(signal.SIGALRM, expired)
        signal.setitimer(signal.ITIMER_REAL, timeout_s)
    try:
        ray.init(**kwargs)
    except _RayStartExpired:
        with contextlib.suppress(Exception):
            ray.shutdown()
        what = "start a local Ray instance" if address == "local" else f"connect to the Ray cluster at {address}"
        raise UnavailableError(f"could not {what} within {timeout_s:g} s (set PROBECOMMIT_RAY_TIMEOUT_S to wait longer)"
                           ) from None
    except (ConnectionError, TimeoutError) as exc:
        raise UnavailableError(f"cannot reach the Ray cluster at {address!r}: {str(exc).splitlines()[0]}") from None
    finally:
        if timed:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)


@contextlib.contextmanager
def _without_recorded_address(address: str) -> Iterator[None]:
    """For ``local``: no ``RAY_ADDRESS`` while Ray starts, so nothing steers it to another cluster."""
    saved = os.environ.pop("RAY_ADDRESS", None) if address == "local" else None
    try:
        yield
    finally:
        if saved is not None:
            os.environ["RAY_ADDRESS"] = saved


@contextlib.contextmanager
def ray_session(address: str, workers: int, timing: dict[str, float],
                timeout_s: float | None = None) -> Iterator[Any]:
    """Connect to (or, for ``"local"``, start a fresh) Ray; shut down on exit what was started here.

    Raises:
        RuntimeError: the cluster cannot be reached or Ray does not start within ``timeout_s``
            (default :data:`RAY_START_TIMEOUT_S`), in one line.
    """
    from probecommit.engines import require

    if address not in ("local", "auto"):
        check_reachable(address)
    ray = require("ray")
    started_here = not ray.is_initialized()
    t0 = time.perf_counter()
    if started_here:
        with _without_recorded_address(address):
            _init_within(ray, ray_init_kwargs(address, workers), address,
                         RAY_START_TIMEOUT_S if timeout_s is None else timeout_s)
    timing["backend_start_s"] = time.perf_counter() - t0
    try:
        yield ray
    finally:
        if started_here:
            ray.shutdown()


def _run_ray(jobs: list[Job], ray: Any) -> Iterator[Result]:
    # Tasks return their tables to the driver: no shared filesystem is needed.
    remote = ray.remote(max_retries=2)(compute_units)
    pending = [remote.remote(*job) for job in jobs]
    while pending:
        done, pending = ray.wait(pending, num_returns=1)
        yield ray.get(done[0])


#: Most episode rows a run may produce (a larger one is a config error, not a study).
MAX_EPISODE_ROWS = 50_000_000
#: Bytes an episode row takes in memory when the final table is merged (measured order, rounded up).
EPISODE_ROW_BYTES = 400


def preflight(config: StudyConfig, concurrency: int = 1, parts: RunParts | None = None) -> InstanceTable:
    """Everything that can fail on a bad config, before anything is written.

    Builds the model, filter and executors (or takes them from ``parts``, the run's own) and
    the simulator (which imports the engine), and draws the instances; returns the instances. The memory estimate is of the whole run: the units
    held at once at the chosen ``concurrency``, and the final tables, read against the
    host's and the container's memory; the output's size is bounded.
    """
    model = (parts or RunParts.build(config)).model
    from probecommit.process.memory import check_fits

    # A unit keeps every budget's belief ([E, N, d] particles + [E, N] weights) and scores
    # [E, A, N] losses for continuous families: estimate before anything is drawn.
    episodes = config.unit_instances * config.repeats
    d, budgets = len(model.latent_names), len(config.probes.commit_budgets) + 2
    per_particle = 8.0 * ((d + 2) * budgets + (0 if model.binary_loss else len(model.action_grid)))
    concurrency = max(1, int(concurrency))
    check_fits(concurrency * episodes * config.belief.particles * per_particle,
               f"{concurrency} work unit(s) at once ({episodes} episodes x {config.belief.particles} particles each)",
               "belief.particles, repeats, unit_instances or the number of workers/threads")
    rows = output_rows(config)
    if rows > MAX_EPISODE_ROWS:
        raise MemoryError(f"the run would write about {rows:,} episode rows, more than the {MAX_EPISODE_ROWS:,} a run "
                          "may hold; reduce instances (count, truths x contexts), repeats, budgets or methods")
    check_fits(rows * EPISODE_ROW_BYTES, f"the run's final tables ({rows:,} episode rows)",
               "instances, repeats, budgets or methods")
    build.build_simulator(config)
    return instance_table(config, model)


def output_rows(config: StudyConfig) -> int:
    """An upper bound on the episode rows of a run: instances x repeats x (budgets + 1) x methods."""
    inst = config.instances
    n = (len(inst.truths) if inst.truths is not None else inst.count) * (len(inst.contexts) if inst.contexts else 1)
    return n * config.repeats * (len(config.probes.commit_budgets) + 1) * len(config.methods)


def run_concurrency(config: StudyConfig, workers: int = 1, ray_address: str | None = None,
                    threads: int | None = None) -> int:
    """Work units held in memory at once on this machine for the chosen backend."""
    if ray_address and ray_address != "local":
        return 1  # units run on the cluster's nodes; the driver holds one result at a time
    if workers > 1 or ray_address == "local":
        return max(1, workers)
    n_threads = unit_threads(config, threads)
    return 2 * n_threads if n_threads > 1 else 1  # _run_threads keeps 2 x threads units in flight


def run_study(
    config: StudyConfig,
    out: str | Path,
    workers: int = 1,
    ray_address: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    threads: int | None = None,
    parts: RunParts | None = None,
    instances: "InstanceTable | pd.DataFrame | None" = None,
) -> StudyResult:
    """Run (or resume) a study into ``out``.

    Results are bit-identical whatever ``workers`` or the backend: every random draw
    is keyed by (seed, instance, repeat), a unit's result does not depend on which
    other units exist, and the final tables are merged in a canonical order.

    Args:
        config: The validated study config.
        out: Run directory; an existing one is resumed only if its config and
            probecommit version match. A complete one whose tables still match its
            manifest is returned as is.
        workers: Local worker processes (1 = in this process); with
            ``ray_address="local"``, the CPUs of the local Ray instance.
        ray_address: Run units on Ray instead: ``"auto"``, ``"local"`` or ``host:port``.
        progress: Called as ``progress(done, total)`` after each unit.
        threads: With ``workers=1`` and no Ray, units run in this many threads of this
            process when the simulator is thread-safe (:func:`unit_threads`; None: the CPUs,
            at most 4, or ``$PROBECOMMIT_ENGINE_THREADS``; 1: one after the other).
        parts: The config's :class:`RunParts` when the caller built them (the CLI, for its own
            :func:`preflight`); else built here. Either way once per run, handed to every unit.
        instances: What :func:`preflight` returned for ``parts`` when the caller ran it; else run here.
    """
    start = time.perf_counter()
    parts = RunParts.build(config) if parts is None else parts
    if instances is None:
        # A bad config fails here, the memory of the whole run at its concurrency too: no directory is created.
        instances = preflight(config, run_concurrency(config, workers, ray_address, threads), parts)
    instances = InstanceTable.of(instances)
    run = RunDir(out)
    config_yaml = dump_config(config)
    run.check_writable(config_yaml)  # an incompatible directory too
    n_units = len(unit_names(len(instances), config.unit_instances))

    def complete() -> StudyResult | None:
        if run.is_complete() and not run.verify_digests():
            if progress:
                progress(n_units, n_units)
            return StudyResult(run.path, run.manifest(), run.final_episodes_table())
        return None

    if (done := complete()) is not None:
        logger.info("%s is complete and unaltered: nothing to run", run.path)
        return done
    timing: dict[str, float] = {"backend_start_s": 0.0}
    with contextlib.ExitStack() as stack:
        # Reach the cluster before writing anything: an unreachable one leaves no directory.
        ray = stack.enter_context(ray_session(ray_address, workers, timing)) if ray_address else None
        stack.enter_context(run.writing(config_yaml))
        if (done := complete()) is not None:  # finished by another process meanwhile
            return done
        return _run_units(parts, run, instances, workers, ray, ray_address, timing, progress, start, threads)


def _groups(parts: "RunParts | dict", instances: "InstanceTable | pd.DataFrame", todo: list[tuple[str, slice]], repeats: int,
            parallel: int, particles: int = GROUP_PARTICLES) -> list[Job]:
    """The jobs: consecutive units to compute, in groups of about :data:`GROUP_EPISODES` episodes
    (:func:`compute_units`), and with several workers or threads, at least two groups each."""
    if not todo:
        return []
    instances = InstanceTable.of(instances)
    per_unit = max(1, max(sl.stop - sl.start for _, sl in todo) * repeats)
    size = max(1, (GROUP_EPISODES * GROUP_PARTICLES) // (per_unit * max(particles, GROUP_PARTICLES)))
    if parallel > 1:  # enough groups to keep every worker busy
        size = max(1, min(size, math.ceil(len(todo) / (2 * parallel))))
    # As many groups as ``size`` needs, of sizes differing by one at most (120 units: 8 of 15, not 7
    # of 16 and one of 8), so threads that take groups in turn finish together.
    n_groups = math.ceil(len(todo) / size)
    bounds = [len(todo) * g // n_groups for g in range(n_groups + 1)]
    jobs = []
    for first, stop in zip(bounds, bounds[1:]):
        group = todo[first:stop]
        rows = np.concatenate([np.arange(sl.start, sl.stop) for _, sl in group])
        contiguous = rows[-1] - rows[0] + 1 == len(rows)  # the usual case: a slice, not a gather
        jobs.append((parts, instances.rows(slice(rows[0], rows[-1] + 1) if contiguous else rows),
                     [(name, sl.stop - sl.start) for name, sl in group]))
    return jobs


def _run_units(parts: RunParts, run: RunDir, instances, workers, ray, ray_address, timing, progress, start,
               threads: int | None = None) -> StudyResult:
    config = parts.config
    units = unit_names(len(instances), config.unit_instances)
    stored = run.done_units()  # refuses batches of other code: a run never mixes two builds
    todo = [(name, sl) for name, sl in units if name not in stored]
    done = len(units) - len(todo)
    if progress:
        progress(done, len(units))
    n_threads = unit_threads(config, threads) if ray is None and workers <= 1 else 1
    jobs = _groups(parts, instances, todo, config.repeats, max(workers, n_threads), config.belief.particles)
    if ray is not None:
        results: Iterable[Result] = _run_ray(jobs, ray)
        backend = f"ray:{ray_address}"
    elif workers > 1 and len(jobs) > 1:
        results = _run_processes(jobs, workers)
        backend = f"processes:{min(workers, len(jobs))}"
    elif len(jobs) > 1 and n_threads > 1:
        results = _run_threads(jobs, n_threads)
        backend = f"threads:{min(n_threads, len(jobs))}"
    else:
        results = _run_serial(jobs)
        backend = "serial"
    logger.info("%s: %d of %d units to run (%d done before), backend %s, engine %s", run.path, len(jobs), len(units),
                done, backend, config.simulator.engine)
    t_units = time.perf_counter()
    try:
        for group in results:
            for unit, tables, stats in group:
                run.add_unit(unit, tables, stats, commit=False)  # only the driver writes, a batch at a time
                logger.debug("unit %s done (%d rows of episodes)", unit, len(tables.get("episodes", ())))
            run.commit_if_due()  # a group's units go into one batch (its first unit holds the group's stats)
            done += len(group)
            if progress:
                progress(done, len(units))
    except Exception:
        run.flush()  # the units finished before the error are kept for the resume
        raise
    run.flush()  # the last batch
    units_wall = time.perf_counter() - t_units
    stats = [run.unit_stats(name) for name, _ in units]
    calls: dict[str, int] = {}
    for s in stats:
        for key, value in s["engine_calls"].items():
            calls[key] = calls.get(key, 0) + value
    manifest = run.finalize(
        [name for name, _ in units],
        {
            "study": config.name,
            "engine": config.simulator.engine,
            "engine_calls": calls,
            "backend": backend,
            "timing": {
                "engine_s": float(sum(s["engine_s"] for s in stats)),
                "units_wall_s": float(sum(s["wall_s"] for s in stats)),
                "backend_start_s": float(timing["backend_start_s"]),
                "this_invocation_units_wall_s": units_wall,
                "this_invocation_wall_s": time.perf_counter() - start,
            },
            "units": len(units),
            "episodes": int(sum(s["episodes"] for s in stats)),
            "failed_trajectories": int(sum(s["failed_trajectories"] for s in stats)),
            "failed_rows": int(sum(s["failed_rows"] for s in stats)),
            "resumed_units": len(units) - len(todo),
        },
    )
    return StudyResult(run.path, manifest, run.final_episodes_table())
