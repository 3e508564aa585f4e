"""Drive a robot through probe-then-commit online, with a crash-safe log (paper Sec. V-D).

Independent of any robot middleware: the robot's own code calls

>>> session = Session.open("runs/rig-day1", config)          # doctest: +SKIP
>>> session.start_episode(position="p03", taps=3)             # doctest: +SKIP
>>> while (u := session.next_probe()) is not None:            # doctest: +SKIP
...     session.observe(u, robot.tap(u))
>>> decision = session.decide()                               # doctest: +SKIP
>>> robot.insert(decision.action)                             # doctest: +SKIP
>>> session.record_outcome(entered=robot.entered())           # doctest: +SKIP
>>> session.record_truth("p03", [x_measured, c_nominal])      # doctest: +SKIP

Probes come from the frozen schedule (``probes.schedule``: ``random`` draws from the
grid with the episode's own seed, or a fixed list), never from the belief, so a log
replays under any model (:mod:`probecommit.robot.replay`). Every call appends a
record to the log before it returns; reopening a log resumes where it stopped, the
belief of an unfinished episode rebuilt from its recorded taps.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from probecommit import __version__
from probecommit.accel import production
from probecommit.core.belief import BeliefState, ParticleFilter
from probecommit.core.executors import ProbeRobust
from probecommit.core.retained import masked_interval
from probecommit.robot.log import LOG_FORMAT, SessionLog, SessionLogError, log_path, read_records
from probecommit.runner.build import build_filter, build_model
from probecommit.runner.config import StudyConfig, config_data, load_config, parse_config
from probecommit.errors import UserError

#: Grid matching tolerance for a probe or an action (in the probe's units).
GRID_TOLERANCE = 1e-6


class SessionError(UserError, ValueError):
    """A call out of order or with bad input; the message says what and what was recorded."""


@dataclass(frozen=True)
class Decision:
    """What :meth:`Session.decide` committed to.

    Attributes:
        episode: Episode number.
        k: Probes assimilated.
        action: The committed action (a float for a 1-D action).
        action_index: Its index on the action grid.
        score: Its scenario failure fraction (or max miss) over the retained set.
        retained: The retained set's interval in the decision coordinate.
        hull: The particle hull in the decision coordinate.
        n_retained: Particles in the retained set.
        seconds: Wall time of the decision.
    """

    episode: int
    k: int
    action: Any
    action_index: int
    score: float
    retained: tuple[float, float]
    hull: tuple[float, float]
    n_retained: int
    seconds: float


@dataclass
class EpisodeRecord:
    """One episode as the log holds it."""

    episode: int
    position: str
    taps: int
    probes: list[list[float]] = field(default_factory=list)
    #: The episode's observed context (a target), for a family that has one; None otherwise.
    context: list[float] | None = None
    readings: list[list[float]] = field(default_factory=list)
    decision: dict[str, Any] | None = None
    outcome: dict[str, Any] | None = None

    @property
    def done(self) -> bool:
        return self.outcome is not None


def as_config(config: StudyConfig | Mapping[str, Any] | str | Path) -> StudyConfig:
    if isinstance(config, StudyConfig):
        return config
    if isinstance(config, Mapping):
        return parse_config(dict(config))
    return load_config(config)


def scheduled_probes(config: StudyConfig, model: Any, episode: int, taps: int) -> np.ndarray:
    """The probes of an episode ``[taps, p]``: a function of the config and the episode number only.

    Raises:
        SessionError: an adaptive schedule (it would depend on the belief) or a fixed
            list shorter than ``taps``.
    """
    schedule = config.probes.schedule
    grid = np.asarray(model.probe_grid, dtype=float)
    if schedule == "adaptive":
        raise SessionError("a session's probes may not depend on the belief (its log must replay under any model); "
                           "use probes.schedule: random or a fixed list")
    if schedule == "random":
        rng = np.random.default_rng([config.seed, episode, 1])
        return grid[rng.integers(grid.shape[0], size=taps)]
    fixed = np.asarray(schedule, dtype=float).reshape(len(schedule), -1)
    if fixed.shape[0] < taps:
        raise SessionError(f"the fixed probe schedule has {fixed.shape[0]} probes, fewer than the {taps} taps asked for")
    return fixed[:taps]


def episode_filter_rng(config: StudyConfig, episode: int) -> np.random.Generator:
    """The generator of an episode's belief (initial particles, resampling, jitter)."""
    return np.random.default_rng([config.seed, episode, 2])


def episode_belief(pfilter: ParticleFilter, config: StudyConfig, episode: int,
                   probes: Sequence[Sequence[float]], readings: Sequence[Sequence[float]]) -> tuple[BeliefState, np.random.Generator]:
    """The belief of an episode after its recorded probes (the session's and replay's one code path)."""
    rng = episode_filter_rng(config, episode)
    state = pfilter.initial([rng])
    for u, y in zip(probes, readings):
        state = pfilter.update(state, np.asarray(u, dtype=float)[None, :], np.asarray(y, dtype=float)[None, :], [rng])
    return state, rng


def decide_belief(model: Any, config: StudyConfig, state: BeliefState,
                  context: Sequence[float] | None = None) -> dict[str, Any]:
    """Probe-Robust's commitment on a one-episode belief (with its context, if the family has one),
    as a decide record's fields."""
    executor = ProbeRobust(model, plateau=config.calibration.plateau, kernels=production().sets)
    ctx = None if context is None else np.asarray(context, dtype=float).reshape(1, -1)
    commit = executor.act(state.particles, state.weights, config.belief.nu, ctx)
    index = int(commit.index[0])
    action = np.asarray(model.action_grid, dtype=float)[index]
    hull_lo, hull_hi = masked_interval(model.decision(state.particles), np.ones_like(state.log_weights, dtype=bool))
    return {
        "action": action.tolist(), "action_index": index, "predicted": float(commit.score[0]),
        "retained_lo": float(commit.lo[0]), "retained_hi": float(commit.hi[0]),
        "hull_lo": float(hull_lo[0]), "hull_hi": float(hull_hi[0]), "n_retained": int(commit.mask[0].sum()),
    }


def _on_grid(value: np.ndarray, grid: np.ndarray) -> int | None:
    hit = np.flatnonzero(np.all(np.abs(grid - value[None, :]) <= GRID_TOLERANCE, axis=1))
    return int(hit[0]) if hit.size else None


class Session:
    """An online probe-then-commit session backed by an append-only log.

    Use :meth:`open`; see the module docstring for the loop. Not thread-safe; one
    process writes a log at a time (a second gets :class:`~probecommit.robot.log.SessionLocked`).
    """

    def __init__(self, log: SessionLog, config: StudyConfig, records: list[dict[str, Any]]) -> None:
        self._log = log
        self.config = config
        self.model = build_model(config)
        self.filter = build_filter(self.model, config.belief)
        self.episodes: dict[int, EpisodeRecord] = {}
        self.truths: dict[str, list[float]] = {}
        self._state: BeliefState | None = None
        self._rng: np.random.Generator | None = None
        self._schedule: np.ndarray | None = None
        for record in records[1:]:
            self._apply(record)
        current = self.current
        if current is not None and current.decision is None:
            self._rebuild(current)
        self._warm_up()

    def _warm_up(self) -> None:
        # The first commit in a process loads the compiled kernels (a few hundred ms); pay it
        # here, on a throwaway prior belief with its own generator, not at the robot's commit.
        state = self.filter.initial([np.random.default_rng(0)])
        context = [1.0] * len(self.model.context_names) or None  # any finite context loads the same kernels
        decide_belief(self.model, self.config, state, context)

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(cls, path: str | Path, config: StudyConfig | Mapping[str, Any] | str | Path | None = None, *,
             repair: bool = False) -> "Session":
        """Open a new session log, or resume an existing one.

        Args:
            path: The log file (``.jsonl``) or a directory (``<dir>/session.jsonl``).
            config: The study config (object, mapping, or YAML path). Required for a new
                log; for an existing one it must match the config in its header (or be None).
            repair: Move a cut-off last line (a crash mid-write) to ``<log>.partial`` and go on.

        Raises:
            SessionLocked: another process is writing this log.
            SessionLogError: the log is malformed (line named), or the config differs.
        """
        log = SessionLog(path)
        log.acquire()
        try:
            if log.path.exists() and log.path.stat().st_size > 0:
                records, partial = read_records(log.path, allow_partial=repair)
                if partial:
                    log.move_partial(partial)
                stored = parse_config(records[0]["config"])
                if config is not None:
                    given = as_config(config)
                    if config_data(given) != config_data(stored):
                        raise SessionLogError(f"{log.path}: the config given differs from the one this log was "
                                              "started with; open it without a config to resume it as recorded")
                return cls(log, stored, records)
            if config is None:
                raise SessionLogError(f"{log.path}: no such session log; give a config to start one")
            config = as_config(config)
            header = {"type": "header", "format": LOG_FORMAT, "version": __version__,
                      "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "config": config_data(config)}
            log.append(header)
            return cls(log, config, [header])
        except BaseException:
            log.release()
            raise

    def close(self) -> None:
        """Release the log (records are already on disk)."""
        self._log.release()

    def __enter__(self) -> "Session":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    @property
    def path(self) -> Path:
        return self._log.path

    @property
    def current(self) -> EpisodeRecord | None:
        """The episode in progress (started, no outcome yet), or None."""
        if not self.episodes:
            return None
        last = self.episodes[max(self.episodes)]
        return None if last.done else last

    # ------------------------------------------------------------------ replaying the log into state
    def _apply(self, record: dict[str, Any]) -> None:
        """Apply one (field-checked) record to the state, under the rules the writing calls enforce.

        The episode state machine: ``episode`` (numbered one past the last, the previous
        one closed) -> ``observe`` x taps (on the probe grid, readings of the model's
        dimension and range) -> ``decide`` (all taps seen; an action of the action grid;
        a binary task's score in [0, 1]) -> ``outcome``. A record out of this order, or
        one another family's model could not have written, is an error naming its line.
        """
        kind = record["type"]
        where = f"{self.path}: line {record.get('_line', '?')}"
        if kind == "episode":
            number = int(record["episode"])
            expected = max(self.episodes) + 1 if self.episodes else 0
            if number != expected:
                raise SessionLogError(f"{where}: episode {number} where the session would number the next one "
                                      f"{expected} (an episode number repeated or skipped)")
            if self.current is not None:
                raise SessionLogError(f"{where}: episode {number} starts while episode {self.current.episode} is "
                                      "still open (a session finishes an episode before starting another)")
            context = record.get("context")
            self.episodes[number] = EpisodeRecord(number, str(record["position"]).strip(), int(record["taps"]),
                                                  context=None if context is None else list(context))
        elif kind in ("observe", "decide", "outcome"):
            ep = self.episodes.get(int(record["episode"]))
            if ep is None:
                raise SessionLogError(f"{where}: a {kind} record for episode {record['episode']!r}, which was never started")
            if ep is not self.current:
                raise SessionLogError(f"{where}: a {kind} record for episode {ep.episode}, which is closed")
            getattr(self, f"_apply_{kind}")(ep, record, where)
        elif kind == "truth":
            names = self.model.latent_names
            if len(record["theta"]) != len(names):
                raise SessionLogError(f"{where}: truth record: theta has {len(record['theta'])} value(s), this "
                                      f"family has {len(names)} ({', '.join(names)})")
            self.truths[str(record["position"]).strip()] = [float(v) for v in record["theta"]]

    def _apply_observe(self, ep: EpisodeRecord, record: dict[str, Any], where: str) -> None:
        if ep.decision is not None:
            raise SessionLogError(f"{where}: an observe record after episode {ep.episode}'s decision")
        if len(ep.probes) >= ep.taps:
            raise SessionLogError(f"{where}: episode {ep.episode} has more observe records than its {ep.taps} taps")
        if "j" in record and record["j"] != len(ep.probes) + 1:
            raise SessionLogError(f"{where}: observe record numbered j={record['j']}, expected {len(ep.probes) + 1}")
        grid = np.asarray(self.model.probe_grid, dtype=float)
        u = np.asarray(record["u"], dtype=float)
        if u.shape[0] != grid.shape[1] or _on_grid(u, grid) is None:
            raise SessionLogError(f"{where}: observe record: probe {record['u']} is not on this family's probe grid "
                                  f"({self.config.family}); the header names another task or the log was altered")
        y = np.asarray(record["y"], dtype=float)
        low, high = getattr(self.model, "observation_range", (-np.inf, np.inf))
        if y.shape[0] != self.model.observation_dim or np.any(y < low) or np.any(y > high):
            raise SessionLogError(f"{where}: observe record: reading {record['y']} is not {self.model.observation_dim} "
                                  f"number(s) in [{low:g}, {high:g}]")
        ep.probes.append(u.tolist())
        ep.readings.append(y.tolist())

    def _apply_decide(self, ep: EpisodeRecord, record: dict[str, Any], where: str) -> None:
        if ep.decision is not None:
            raise SessionLogError(f"{where}: a second decide record for episode {ep.episode}")
        if len(ep.probes) != ep.taps or record["k"] != len(ep.probes):
            raise SessionLogError(f"{where}: decide record with k={record['k']} after {len(ep.probes)} of "
                                  f"{ep.taps} taps (a session decides after all of its taps)")
        grid = np.asarray(self.model.action_grid, dtype=float).reshape(len(self.model.action_grid), -1)
        index = record["action_index"]
        action = np.asarray(record["action"], dtype=float)
        if index >= grid.shape[0] or action.shape[0] != grid.shape[1] or \
                not np.all(np.abs(grid[index] - action) <= GRID_TOLERANCE):
            raise SessionLogError(f"{where}: decide record: action {record['action']} is not action "
                                  f"{index} of this family's grid ({self.config.family})")
        if getattr(self.model, "binary_loss", False) and record["predicted"] > 1:
            raise SessionLogError(f"{where}: decide record: predicted {record['predicted']!r} is not a failure "
                                  "fraction in [0, 1]")
        ep.decision = {k: v for k, v in record.items() if k not in ("type", "_line")}

    def _apply_outcome(self, ep: EpisodeRecord, record: dict[str, Any], where: str) -> None:
        if ep.decision is None:
            raise SessionLogError(f"{where}: an outcome record for episode {ep.episode}, which never decided")
        ep.outcome = {k: v for k, v in record.items() if k not in ("type", "_line")}

    def _rebuild(self, ep: EpisodeRecord) -> None:
        self._schedule = scheduled_probes(self.config, self.model, ep.episode, ep.taps)
        self._state, self._rng = episode_belief(self.filter, self.config, ep.episode, ep.probes, ep.readings)

    def _reject(self, call: str, reason: str, **fields: Any) -> SessionError:
        safe = {k: (repr(v) if isinstance(v, float) and not np.isfinite(v) else v) for k, v in fields.items()}
        safe = {k: ([repr(x) if isinstance(x, float) and not np.isfinite(x) else x for x in v] if isinstance(v, list) else v)
                for k, v in safe.items()}
        self._log.append({"type": "rejected", "call": call, "reason": reason, "t": time.time(), **safe})
        return SessionError(f"{reason} (recorded in {self.path.name} as rejected; nothing was assimilated)")

    # ------------------------------------------------------------------ the loop
    def _check_context(self, context: Sequence[float] | float | None) -> list[float] | None:
        names = self.model.context_names
        if not names:
            if context is not None:
                raise SessionError(f"the {self.model.name} family has no context; start_episode takes none")
            return None
        values = None if context is None else np.atleast_1d(np.asarray(context, dtype=float)).reshape(-1)
        if values is None or values.shape[0] != len(names) or not np.all(np.isfinite(values)):
            raise SessionError(f"the {self.model.name} family needs a context of {len(names)} finite number(s) "
                               f"({', '.join(names)}) per episode: start_episode(..., context=...)")
        return values.tolist()

    def start_episode(self, position: str, taps: int, context: Sequence[float] | float | None = None) -> int:
        """Begin an episode at a block position with a tap budget; returns its number.

        Args:
            position: Label of the placement (episodes at one position share a truth).
            taps: Probe budget of the episode.
            context: The episode's observed context (a target distance) for a family that has
                one (``model.context_names``); None for a family without.
        """
        if self.current is not None:
            ep = self.current
            state = "decided, no outcome recorded" if ep.decision else f"{len(ep.probes)} of {ep.taps} taps"
            raise SessionError(f"episode {ep.episode} is still open ({state}); finish it before starting another")
        if not isinstance(taps, (int, np.integer)) or not 0 <= taps <= 64:
            raise SessionError(f"taps must be an integer in 0..64, got {taps!r}")
        position = str(position).strip()
        if not position:
            raise SessionError("position must be a non-empty label of the block's placement")
        ctx = self._check_context(context)
        number = max(self.episodes) + 1 if self.episodes else 0
        record = {"type": "episode", "episode": number, "position": position, "taps": int(taps), "t": time.time()}
        if ctx is not None:
            record["context"] = ctx
        self._log.append(record)
        ep = EpisodeRecord(number, position, int(taps), context=ctx)
        self.episodes[number] = ep
        self._rebuild(ep)
        return number

    def _require_open(self, call: str) -> EpisodeRecord:
        ep = self.current
        if ep is None:
            raise SessionError(f"{call}: no episode in progress; call start_episode first")
        return ep

    def next_probe(self) -> Any:
        """The next scheduled probe (a float for a 1-D probe), or None once the budget is spent."""
        ep = self._require_open("next_probe")
        j = len(ep.probes)
        if ep.decision is not None or j >= ep.taps:
            return None
        u = self._schedule[j]
        return float(u[0]) if u.size == 1 else u.copy()

    def observe(self, u: Any, y: Any) -> None:
        """Record and assimilate one probe ``u`` and its reading ``y``.

        Raises:
            SessionError: out of order, a probe off the grid, or a reading that is
                non-finite or outside the physical range; the bad call is recorded as
                ``rejected`` and nothing is assimilated.
        """
        ep = self._require_open("observe")
        u_arr = np.atleast_1d(np.asarray(u, dtype=float)).reshape(-1)
        y_arr = np.atleast_1d(np.asarray(y, dtype=float)).reshape(-1)
        fields = {"episode": ep.episode, "u": u_arr.tolist(), "y": y_arr.tolist()}
        if ep.decision is not None:
            raise self._reject("observe", f"episode {ep.episode} has already committed; a probe after the commit "
                               "cannot change it", **fields)
        if len(ep.probes) >= ep.taps:
            raise self._reject("observe", f"episode {ep.episode} has all of its {ep.taps} taps", **fields)
        grid = np.asarray(self.model.probe_grid, dtype=float)
        if u_arr.shape[0] != grid.shape[1] or not np.all(np.isfinite(u_arr)) or _on_grid(u_arr, grid) is None:
            raise self._reject("observe", f"probe {u_arr.tolist()} is not on the probe grid "
                               f"({', '.join(f'{v:g}' for v in grid[:, 0])}{'...' if grid.shape[1] > 1 else ''})", **fields)
        if y_arr.shape[0] != self.model.observation_dim or not np.all(np.isfinite(y_arr)):
            raise self._reject("observe", f"reading {y_arr.tolist()} is not {self.model.observation_dim} finite "
                               "number(s)", **fields)
        low, high = self.model.observation_range
        if np.any(y_arr < low) or np.any(y_arr > high):
            raise self._reject("observe", f"reading {y_arr.tolist()} is outside the physical range [{low:g}, {high:g}]",
                               **fields)
        scheduled = self._schedule[len(ep.probes)]
        record = {"type": "observe", **fields, "j": len(ep.probes) + 1, "t": time.time()}
        if not np.allclose(scheduled, u_arr, atol=GRID_TOLERANCE):
            record["scheduled"] = scheduled.tolist()
        self._log.append(record)
        ep.probes.append(u_arr.tolist())
        ep.readings.append(y_arr.tolist())
        self._state = self.filter.update(self._state, u_arr[None, :], y_arr[None, :], [self._rng])

    def decide(self) -> Decision:
        """Commit: Probe-Robust over the retained set of the current belief (logged before it returns)."""
        ep = self._require_open("decide")
        if ep.decision is not None:
            raise SessionError(f"episode {ep.episode} has already committed to {ep.decision['action']}")
        if len(ep.probes) < ep.taps:
            raise SessionError(f"episode {ep.episode} has {len(ep.probes)} of its {ep.taps} taps; observe the rest first")
        start = time.perf_counter()
        fields = decide_belief(self.model, self.config, self._state, ep.context)
        seconds = time.perf_counter() - start
        record = {"type": "decide", "episode": ep.episode, "k": len(ep.probes), **fields, "decide_s": seconds,
                  "t": time.time()}
        self._log.append(record)
        ep.decision = {k: v for k, v in record.items() if k != "type"}
        action = fields["action"][0] if len(fields["action"]) == 1 else np.asarray(fields["action"])
        return Decision(ep.episode, len(ep.probes), action, fields["action_index"], fields["predicted"],
                        (fields["retained_lo"], fields["retained_hi"]), (fields["hull_lo"], fields["hull_hi"]),
                        fields["n_retained"], seconds)

    def record_outcome(self, *, entered: bool | None = None, truth: Sequence[float] | None = None,
                       **notes: Any) -> None:
        """Record what happened after the commit; closes the episode.

        Args:
            entered: Whether the tool physically entered (None if not observed).
            truth: The measured latents of this episode's position, if known now
                (else give them later with :meth:`record_truth`).
            notes: Anything else worth keeping (JSON-serializable).
        """
        ep = self._require_open("record_outcome")
        if ep.decision is None:
            raise SessionError(f"episode {ep.episode} has not committed yet; call decide first")
        if truth is not None:
            self.record_truth(ep.position, truth)
        self._log.append({"type": "outcome", "episode": ep.episode,
                          "entered": None if entered is None else bool(entered), "notes": notes, "t": time.time()})
        ep.outcome = {"entered": entered, "notes": notes}
        self._state = None

    def record_truth(self, position: str, theta: Sequence[float]) -> None:
        """Record the measured latents of a block position (e.g. from a touch sweep after the run).

        Raises:
            SessionError: the wrong number of latents or a non-finite value (recorded as rejected).
        """
        values = np.atleast_1d(np.asarray(theta, dtype=float)).reshape(-1)
        names = self.model.latent_names
        if values.shape[0] != len(names) or not np.all(np.isfinite(values)):
            raise self._reject("record_truth", f"truth {values.tolist()} must be {len(names)} finite number(s) "
                               f"({', '.join(names)})", position=str(position), theta=values.tolist())
        self._log.append({"type": "truth", "position": str(position), "theta": values.tolist(), "t": time.time()})
        self.truths[str(position)] = values.tolist()

    def note(self, text: str, **fields: Any) -> None:
        """Append a free-form note (an operator's remark, a rig event)."""
        self._log.append({"type": "note", "text": str(text), **fields, "t": time.time()})


def load_session(path: str | Path) -> tuple[StudyConfig, dict[int, EpisodeRecord], dict[str, list[float]], Path]:
    """Read a session log without opening it for writing: ``(config, episodes, truths, path)``.

    A cut-off last line is ignored here (it never returned to its caller) and said in
    the returned episodes' absence; reading never modifies the log.
    """
    path = log_path(path)
    if not path.is_file():
        raise SessionLogError(f"{path}: no such session log")
    records, _ = read_records(path, allow_partial=True)
    config = parse_config(records[0]["config"])
    view = Session.__new__(Session)
    view._log = SessionLog(path)  # not acquired: read only
    view.config = config
    view.model = build_model(config)
    view.episodes, view.truths = {}, {}
    for record in records[1:]:
        view._apply(record)
    return config, view.episodes, view.truths, path
