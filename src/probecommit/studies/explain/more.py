"""The second and third helpers' explain steps (E30..), run after the others by ``Explain.run``.

Each step writes one result group of ``explain:results`` and reads only what ``Explain``
already holds (the protocol, the root's frozen runs, the bootstrap settings, the config).
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from probecommit.runner.aside import in_own_process
from probecommit.studies.explain import breadth, engines_x, grasp_x, mixture_x, pybullet_x, rig, searches
from probecommit.studies.insertion import ROBUST_FILE
from probecommit.studies.paper_values import PAPER, value

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("engines_x", "searches", "rig_redraws", "breadth_prior", "pybullet_escape", "mixture_noise", "grasp_signs")


def run(job: Any) -> None:
    """Every step, in order of cost (cheapest first)."""
    job.res["engines_x"].update(engines_x.run(job.root))
    job.progress("explain: development searches resampled", 0, 1)
    s = job.res["searches"]
    job.stored[searches.COVER_STORED] = searches.cover_table(job.p)
    s.update(search_keys(job.stored[searches.COVER_STORED], pd.read_parquet(job.root / "insertion" / "results" / ROBUST_FILE),
                         job.boot))
    job.progress("explain: the simulated rig redrawn (in a process of its own, beside the later steps)", 0, 1)

    def rig_done(result: tuple[dict[str, Any], dict[str, pd.DataFrame]]) -> None:
        job.res["rig_redraws"].update(result[0])
        job.stored.update(result[1])

    job.submit(rig_done, rig.run, job.runs, job.cfg, job.boot, job.quick)
    job.progress("explain: Table II's families over the prior's width", 0, 1)  # in place: ex4's cone reads its runs
    keys, job.tables["breadth_prior"] = breadth.run(job.root, job.runs, job.cfg, job.boot, job.quick)
    job.res["breadth_prior"].update(keys)
    run_ex3(job)


def search_keys(cover: pd.DataFrame, robust: pd.DataFrame, boot: dict[str, Any]) -> dict[str, Any]:
    """``searches.*``: the cover search from its stored rows, the robust filters' tuning from the insertion study's
    stored tuning rows (``robust_episodes.parquet``), each resampled over development instances."""
    paper = {f: value(f"T42-robust-chosen.{f}") for f in ("tempering", "mixture", "rejuvenation")}
    out = {f"cover.{k}": v for k, v in searches.cover_stability(cover, PAPER["cover.schedule"], boot).items()}
    tuning = robust[robust["part"] == "tuning"]
    return {**out, **{f"robust.{k}": v for k, v in searches.robust_stability(tuning, paper, boot).items()}}


def run_ex3(job: Any) -> None:
    """The third helper's steps (E45..)."""
    job.aside(pybullet_escape, needs=("engines",))()  # PyBullet draws only this group reads: set aside
    job.aside(mixture_noise, needs=())()  # replays of the insertion study's run only: in a process of its own
    job.progress("explain: grasp on the model-exact scene", 0, 1)
    # in a process of its own: the study's units took the explain process from about 600 to 647 MB (issue 42)
    job.stored[grasp_x.STORED] = in_own_process(grasp_x.run, job.runs, job.quick, job.workers)
    job.res["grasp_signs"].update(grasp_x.keys(job.stored[grasp_x.STORED]))  # what verify recomputes


def mixture_noise(job: Any) -> None:
    """The mixture against the filter's own noise (``mixture_x``): the harness's base run replayed per filter seed."""
    job.progress("explain: the mixture against the filter's own noise", 0, 1)
    r, seeds = job.p.robust, job.cfg["mixture_filter_seeds_quick" if job.quick else "mixture_filter_seeds"]
    base = job.load("faults_base")
    mixture = {"likelihood": "mixture", "epsilon": value("T42-robust-chosen.mixture"),
               "mixture_low": r.mixture_range[0], "mixture_high": r.mixture_range[1]}
    keys, job.tables["mixture_noise"] = mixture_x.run(base, mixture, [base.config.seed + i for i in range(1, seeds + 1)],
                                                      job.p.budgets["random"])
    job.res["mixture_noise"].update(keys)


def pybullet_escape(job: Any) -> None:
    """PyBullet's reported scene properties (``pybullet_x``): fresh PyBullet draws of the engines study's run."""
    job.progress("explain: PyBullet's reported scene properties", 0, 1)
    draws = job.cfg["pybullet_draws_quick" if job.quick else "pybullet_draws"]
    job.res["pybullet_escape"].update(pybullet_x.run(job.root, job.runs, job.boot, job.workers, draws=draws,
                                                     stored_rows=job.stored))
