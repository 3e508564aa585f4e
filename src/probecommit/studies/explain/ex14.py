"""The ex14 helper's steps (E112..E114), run by ``Explain.run``: k = 1 escape as a band event and the readings
of the paper's filter sentence, on Table III's random test run and T36's paper's-schedule test run.

Replays of stored taps and readings under each reading (``ex14_escape``), no engine run: the two
belief-changing readings re-commit the original arm at Table III's budgets (aims from the run's engine
cache). The rows are stored beside ``results.json`` so ``verify`` recomputes every key (``recompute``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.explain import ex14_escape, ex14_summary

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex14_escape", "ex14_audit", "ex14_surprise")
#: The rows each group's keys are summarized from (stored beside ``results.json``).
STORED_BY_GROUP = dict.fromkeys(GROUPS, ex14_summary.STORED)
#: Table III's budgets.
AUDIT_BUDGETS = (1, 2, 3, 5, 8)
#: Readings that change the belief (re-committed); ``prejitter`` only measures the stated belief otherwise.
BELIEF_READINGS = ("duplicates", "every_step")
KEY = ["instance_id", "repeat", "k"]


#: The band's inputs, stored on every row of the random run (a closed form of the run's config).
BAND_COLUMNS = ("x_low", "x_high", "c_low", "c_high", "sim_offset")


def band_inputs(config: Any) -> dict[str, float]:
    """The run's prior box and the simulator's boundary offset (what the exact band probability needs)."""
    m = config.model
    return dict(zip(BAND_COLUMNS, (float(m.prior_low[0]), float(m.prior_high[0]), float(m.prior_low[1]),
                                   float(m.prior_high[1]), float(config.simulator.boundary_offset))))


def band_probability(rows: pd.DataFrame) -> float:
    """The exact P(first random tap in the misread band) from the random run's stored band inputs, over the
    insertion model's probe grid."""
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM, InsertionModel, half_gap

    b = rows.loc[rows["run"] == "random", list(BAND_COLUMNS)].iloc[0]
    return ex14_escape.p_band(InsertionModel.probe_grid[:, 0], (b["x_low"], b["x_high"]), (b["c_low"], b["c_high"]),
                              half_gap, -TIP_RADIUS_MM, b["sim_offset"])


def first_tap_band(loaded: Any) -> pd.DataFrame:
    """Per trajectory: whether its first tap lay in its truth's misread band (stored taps and truths)."""
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM, half_gap

    taps = loaded.probes
    first = taps[taps["j"] == 1][["instance_id", "repeat", "u"]]
    t = first.merge(loaded.instances[["instance_id", "true_x_hole", "true_c"]], on="instance_id")
    band = ex14_escape.in_band(t["u"], t["true_x_hole"], half_gap(t["true_c"].to_numpy(float)), -TIP_RADIUS_MM,
                               float(loaded.config.simulator.boundary_offset))
    return pd.DataFrame({"instance_id": t["instance_id"].astype(str), "repeat": t["repeat"].astype("int64"),
                         "in_band": np.asarray(band, bool)})


def random_rows(loaded: Any, chunk: int | None) -> pd.DataFrame:
    """Table III's random test run under every reading: escape as measured, the belief's coverage, realized
    failure and score (stored for the stated belief, re-committed for the belief-changing readings)."""
    from probecommit.runner.replay import RunBeliefs

    beliefs = RunBeliefs.of(loaded, chunk_instances=None)
    stored = loaded.episodes
    stored = stored[(stored["method"] == "probe_robust") & (stored["status"] == "ok")]
    parts = []
    for reading in ex14_escape.READINGS:
        rows = ex14_escape.replay_rows(beliefs, reading, AUDIT_BUDGETS)
        source = stored
        if reading in BELIEF_READINGS:
            source = ex14_escape.committed_original(loaded.path, reading, AUDIT_BUDGETS, chunk)
            source = source[source["method"] == "probe_robust"]
        cols = source[KEY + ["covered", "realized", "predicted"]].astype({"instance_id": str, "repeat": "int64"})
        parts.append(rows.merge(cols, on=KEY, how="left", validate="one_to_one"))
    out = pd.concat(parts, ignore_index=True).merge(first_tap_band(loaded), on=["instance_id", "repeat"], how="left")
    return out.assign(run="random", **band_inputs(loaded.config))


def draw_rows(runs: Path) -> pd.DataFrame:
    """E17's fresh draws (``analytic_draw_NN``, stated reading, stored episodes): k = 1 escape and the first
    tap's band, per trajectory (published beside E112, in no rule)."""
    from probecommit.runner.replay import load_run

    parts = []
    for path in sorted(p for p in runs.glob("analytic_draw_[0-9][0-9]") if (p / "episodes.parquet").is_file()):
        loaded = load_run(path)
        e = loaded.episodes
        e = e[(e["method"] == "probe_robust") & (e["status"] == "ok") & (e["k"] == 1)]
        e = e[KEY + ["escaped"]].astype({"instance_id": str, "repeat": "int64"})
        rows = e.merge(first_tap_band(loaded), on=["instance_id", "repeat"], how="left")
        parts.append(rows.assign(run=path.name.removeprefix("analytic_"), reading=ex14_escape.READINGS[0]))
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=[*KEY, "escaped", "in_band", "run", "reading"])


def cover_rows(loaded: Any, budgets: tuple[int, int]) -> pd.DataFrame:
    """T36's paper's-schedule test run under every reading: escape and running-max surprise at both budgets."""
    from probecommit.runner.replay import RunBeliefs

    beliefs = RunBeliefs.of(loaded, chunk_instances=None)
    parts = [ex14_escape.replay_rows(beliefs, r, budgets) for r in ex14_escape.READINGS]
    return pd.concat(parts, ignore_index=True).assign(run="cover")


def summaries(rows: pd.DataFrame, budgets: tuple[int, int], boot: dict[str, int]) -> dict[str, dict[str, Any]]:
    """The three groups' keys from the stored rows."""
    from probecommit.studies.paper_values import value

    escape = ex14_summary.escape_keys(rows, band_probability(rows), value("T11-audit-trend.escape_k1") / 100.0,
                                      value("T11-audit-trend.escape_k8") / 100.0, boot)
    escape.update(ex14_summary.draw_keys(rows))
    return {"ex14_escape": escape, "ex14_audit": ex14_summary.audit_keys(rows, AUDIT_BUDGETS, boot),
            "ex14_surprise": ex14_summary.surprise_keys(rows, budgets, boot)}


def run(job: Any, paper_schedule: dict[str, Any]) -> None:
    """E112..E114 on the insertion study's random test run and the paper's-schedule Split B test run."""
    job.progress("explain: k = 1 escape as a band event; the filter sentence's readings", 0, 1)
    random = job.load("B_test_random")
    budgets = (1, int(job.p.budgets["cover"]))
    rows = pd.concat([random_rows(random, 48), cover_rows(paper_schedule["test"], budgets), draw_rows(job.runs)],
                     ignore_index=True)
    job.stored[ex14_summary.STORED] = rows
    for group, keys in summaries(rows, budgets, job.boot).items():
        job.res[group].update(keys)


def recompute(folder: Path, results: dict[str, Any], boot: dict[str, Any]) -> dict[str, tuple[Any, str]]:
    """``{"<group>.<key>": (value, stored file)}`` of every key these steps publish, from the stored rows (the
    band probability again as the closed form of the stored band inputs)."""
    name = ex14_summary.STORED
    if not (folder / name).is_file() or not results.get("ex14_escape"):
        return {}
    rows = pd.read_parquet(folder / name)
    cover = rows[rows["run"] == "cover"]
    budgets = (int(cover["k"].min()), int(cover["k"].max()))
    out: dict[str, tuple[Any, str]] = {}
    for group, keys in summaries(rows, budgets, boot).items():
        for key, v in keys.items():
            out[f"{group}.{key}"] = (v, name)
    return out
