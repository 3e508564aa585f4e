"""A stand-in robot: the simulated rig driving a :class:`~probecommit.robot.session.Session`.

It runs the loop a physical rig runs (place the block, tap, commit, insert, measure)
against a rig simulator (MuJoCo by default) and writes the same log, so the audit,
Table IX and the fault replays run without hardware, in the tests and in the demo.
Block positions are the study config's instances (``instances.count`` draws from the
truth box); each position gets ``repeats`` episodes at every budget of
``probes.budgets``. Readings use a per-episode generator independent of the belief's.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np

from probecommit.robot.session import Session, as_config
from probecommit.runner.build import build_model, build_simulator
from probecommit.runner.config import StudyConfig
from probecommit.runner.instances import draw_instances


def reading_rng(config: StudyConfig, episode: int) -> np.random.Generator:
    """The simulated rig's generator of one episode's readings (misreads, noise)."""
    return np.random.default_rng([config.seed, episode, 3])


def simulate_session(path: str | Path, config: Any, *, progress: Callable[[int, int], None] | None = None,
                     stop_after: int | None = None, repair: bool = False) -> Path:
    """Run (or resume) the simulated rig's whole session into the log at ``path``.

    Args:
        path: Log file or directory.
        config: Study config (object, mapping or YAML path) of any family (one with a context
            takes each instance's context, ``instances.contexts``).
        progress: Called as ``progress(done, total)`` after each episode.
        stop_after: Stop after this many episodes in this call (a deliberate interruption,
            for tests and demos of resuming).
        repair: Resume a log whose last line was cut off by a crash (kept in ``.partial``).

    Returns:
        The log's path.
    """
    config = as_config(config)
    model = build_model(config)
    simulator = build_simulator(config)
    instances = draw_instances(config, model)
    truths = instances[[f"true_{n}" for n in model.latent_names]].to_numpy()
    contexts = instances[[f"ctx_{n}" for n in model.context_names]].to_numpy() if model.context_names else None
    budgets = config.probes.budgets or [config.probes.budget]
    plan = [(i, r, k) for i in range(len(instances)) for r in range(config.repeats) for k in budgets]
    done_now = 0
    with Session.open(path, config, repair=repair) as session:
        started = len(session.episodes)
        # Resume: an open episode finishes first, then the plan continues where the log stopped.
        for number in range(max(started - 1, 0), len(plan)):
            if stop_after is not None and done_now >= stop_after:
                break
            i, _, k = plan[number]
            position = str(instances["instance_id"].iloc[i])
            if number >= started:
                session.start_episode(position, taps=k, context=None if contexts is None else contexts[i].tolist())
            ep = session.episodes[number]
            theta = truths[i]
            last_of_position = number + 1 == len(plan) or plan[number + 1][0] != i
            if ep.done:  # a crash may have come between the outcome and the touch sweep
                if last_of_position and position not in session.truths:
                    session.record_truth(position, theta)
                continue
            rng = reading_rng(config, number)
            for _ in range(len(ep.probes)):  # readings already recorded were drawn already
                simulator.probe(theta, np.asarray(ep.probes[0], dtype=float), rng)
            while (u := session.next_probe()) is not None:
                session.observe(u, simulator.probe(theta, np.atleast_1d(u), rng))
            decision = session.decide() if ep.decision is None else None
            action = decision.action if decision is not None else ep.decision["action"]
            outcome = simulator.execute(theta, np.atleast_1d(action), None if contexts is None else contexts[i])
            if "entered" in outcome:  # an insertion-like rig: did the tool enter, and how deep
                session.record_outcome(entered=outcome["entered"], depth=outcome.get("depth"))
            else:  # any other family: what its simulator realized (a miss, a failure)
                session.record_outcome(realized=float(outcome["realized"]))
            if last_of_position:  # the touch sweep after the position's episodes gives its truth
                session.record_truth(position, theta)
            done_now += 1
            if progress is not None:
                progress(number + 1, len(plan))
        return session.path
