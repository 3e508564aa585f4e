"""T43's optimism under the robust filters on other draws of the generator (E212, E213; ex37, issue #36; rules
declared in ``docs/decisions.md``, "ex37", before any of their numbers).

Why: T43 says the mixture and rejuvenation filters leave optimism above the paper's floor. On the harness draw the
insertion study measures (its fault harness's base run under the boundary error) all three arms sit below it; E12
replayed Test C (another draw) with the mixture, but the rejuvenation filter was never run off the harness draw.
E212 is E12's twin: Test C's deployed run replayed with the chosen rejuvenation fraction. E213 replays the 12 fresh
harness draws E72 runs (``ex7_robust.harness_draw``) as the insertion study replays its harness
(``insertion.robust``): under the deployed boundary, plain and with each chosen filter, so the draw-to-draw
spread of optimism, and each filter's gap to the deployed arm on the same probes, are measured. Every replay commits
the final budget only (``replay_at``); every key is :func:`summary` of the stored rows (:data:`STORED`).
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from probecommit.studies.paper_values import value as paper_value

#: Result group and its stored rows (the final-budget Probe-Robust rows of every arm, beside results.json).
GROUP = "ex37_filters"
GROUPS = (GROUP,)
STORED = "ex37_filters_rows.parquet"
COLUMNS = ("source", "arm", "instance_id", "repeat", "k", "predicted", "realized", "escaped")
#: The arms of a harness draw: the deployed boundary alone, then with each chosen filter.
ARMS = ("deployed", "mixture", "rejuvenation")
FILTERS = ARMS[1:]
#: Test C's stored deployed run (the insertion study's), E12's source.
TESTC = "C_random"


def arm_overrides(protocol: Any, chosen: Mapping[str, float]) -> dict[str, dict[str, Any]]:
    """The insertion study's harness arms (``insertion.robust``): the deployed boundary, plus each filter at the
    value its development tuning chose (the belief overrides ``robust_candidates`` builds)."""
    from probecommit.studies.robust import robust_candidates

    r = protocol.robust
    grid = robust_candidates(r.temperatures, r.epsilons, r.rejuvenation, r.mixture_range)
    out: dict[str, dict[str, Any]] = {"deployed": {"model": {"boundary": "deployed"}}}
    for family in FILTERS:
        [belief] = [b for value, b in grid[family] if np.isclose(value, float(chosen[family]))]
        out[family] = {"model": {"boundary": "deployed"}, "belief": belief}
    return out


def final_rows(episodes: pd.DataFrame, k: int, source: str, arm: str) -> pd.DataFrame:
    """The ok Probe-Robust rows at budget ``k`` in the stored columns, one source and arm."""
    rows = episodes[(episodes["method"] == "probe_robust") & (episodes["status"] == "ok") & (episodes["k"] == k)]
    rows = rows.assign(source=source, arm=arm)[list(COLUMNS)]
    return rows.sort_values(["instance_id", "repeat"]).reset_index(drop=True)


def draw_rows(loaded: Any, overrides: Mapping[str, dict[str, Any]], k: int, source: str) -> pd.DataFrame:
    """One stored run replayed at budget ``k`` under each arm's overrides (same probes, paired)."""
    from probecommit.studies.explain.replay_final import replay_at

    return pd.concat([final_rows(replay_at(loaded, dict(o), k), k, source, arm) for arm, o in overrides.items()],
                     ignore_index=True)


def testc_rows(loaded: Any, rejuvenation: dict[str, Any], k: int) -> pd.DataFrame:
    """E212's rows: Test C's deployed run as stored, and replayed with the chosen rejuvenation (E12's replay)."""
    from probecommit.studies.explain.replay_final import replay_at

    replay = replay_at(loaded, {"belief": rejuvenation["belief"]}, k)
    return pd.concat([final_rows(loaded.episodes, k, "testc", "deployed"),
                      final_rows(replay, k, "testc", "rejuvenation")], ignore_index=True)


def optimism(rows: pd.DataFrame) -> float:
    """Mean realized minus predicted failure (the insertion study's ``episode_metrics`` optimism)."""
    return float((rows["realized"].to_numpy(float) - rows["predicted"].to_numpy(float)).mean())


def testc_keys(rows: pd.DataFrame) -> dict[str, Any]:
    """E212's keys: Test C's deployed and rejuvenation optimism, and the latter's escape and episodes."""
    arm = lambda name: rows[rows["arm"] == name]  # noqa: E731
    out = {"testc.deployed.optimism": optimism(arm("deployed")), "testc.rejuvenation.optimism": optimism(arm("rejuvenation")),
           "testc.rejuvenation.escape": float(arm("rejuvenation")["escaped"].astype(float).mean()),
           "testc.n": int(len(arm("rejuvenation")))}
    return out


def draws_keys(rows: pd.DataFrame) -> dict[str, Any]:
    """E213's keys: each draw's optimism per arm, each arm's mean, min and max over the draws, and each filter's
    largest |filter - deployed| over the draws (``draws.<f>.max_gap``; E213's rule is the registry's)."""
    per = {(d, a): optimism(part) for (d, a), part in rows.groupby(["source", "arm"], sort=True)}
    names = sorted({d for d, _ in per})
    out: dict[str, Any] = {"draws.count": len(names)}
    out.update({f"draws.{d}.{a}.optimism": v for (d, a), v in per.items()})
    for arm in ARMS:
        got = np.array([per[(d, arm)] for d in names])
        out.update({f"draws.{arm}.optimism.mean": float(got.mean()), f"draws.{arm}.optimism.min": float(got.min()),
                    f"draws.{arm}.optimism.max": float(got.max())})
    for f in FILTERS:
        out[f"draws.{f}.max_gap"] = float(max(abs(per[(d, f)] - per[(d, "deployed")]) for d in names))
    floor = paper_value("T43-robust-filters.optimism_floor")
    above = {f: {d for d in names if per[(d, f)] > floor} for f in FILTERS}
    out.update({f"draws.{f}.above_floor": len(above[f]) for f in FILTERS})
    out["draws.all_filters_above_floor"] = len(set.intersection(*above.values()))  # the paper's sentence on one draw
    return out


def summary(rows: pd.DataFrame) -> dict[str, Any]:
    """Every key of ``explain:results.ex37_filters`` from the stored rows (what verify recomputes)."""
    out: dict[str, Any] = {}
    testc = rows[rows["source"] == "testc"]
    if len(testc):
        out.update(testc_keys(testc))
    draws = rows[rows["source"] != "testc"]
    if len(draws):
        out.update(draws_keys(draws))
    return out


def run(job: Any) -> None:
    """E212 and E213 (set aside after ex7's step, whose harness draws it replays: the same runs, already run)."""
    from probecommit.studies.explain.ex7_robust import harness_draw

    job.progress("explain: the robust filters' optimism on Test C and the harness draws (E212, E213)", 0, 1)
    p = job.p
    k = int(p.budgets["random"])
    arms = arm_overrides(p, job.insertion_results()["robust"]["chosen"])
    parts = [testc_rows(job.load(TESTC), arms["rejuvenation"], k)]
    count = int(job.cfg["ex7_harness_draws_quick" if job.quick else "ex7_harness_draws"])
    for i in range(count):
        job.progress("explain: the robust filters on the harness draws", i, count)
        loaded = harness_draw(p, job.runs, i, job.workers)
        parts.append(draw_rows(loaded, arms, k, loaded.path.name))
    rows = pd.concat(parts, ignore_index=True)
    rows["escaped"] = rows["escaped"].astype("boolean")
    job.stored[STORED] = rows
    job.res[GROUP].update(summary(rows))


__all__: Sequence[str] = ("run", "summary", "testc_keys", "draws_keys", "arm_overrides", "draw_rows", "testc_rows",
                          "final_rows", "optimism")
