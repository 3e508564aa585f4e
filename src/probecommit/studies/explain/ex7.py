"""The fourth session's ex7 explain steps (E69..E72), run last by ``Explain.run``.

Each step writes one result group of ``explain:results`` and reads only what ``Explain`` holds.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from probecommit.studies.explain import ex7_faults, ex7_robust

#: Result groups these steps fill (added to ``Explain.res``).
GROUPS = ("ex7_faults", "ex7_robust")


def run(job: Any) -> None:
    """The fault-harness readings (no engine runs), then the fresh MuJoCo draws of the robust filters."""
    job.progress("explain: the fault harness read over the budget and by class probability", 0, 1)
    ex7_faults.run(job)
    job.progress("explain: the mixture over fresh development and harness draws", 0, 1)
    ex7_robust.run(job)


#: The stored rows :func:`recompute` reads, in the explain folder.
STORED = (ex7_faults.STORED, ex7_robust.STORED_DEV, ex7_robust.STORED_HARNESS)


def recompute(folder: Path, results: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str], list[str]]:
    """ex7's keys recomputed from a publication's stored rows (``verify``): the signatures from the insertion
    study's fault episodes, the surprise AUCs and the draws' summaries from the rows this step stored.

    Returns ``(values, sources, problems)`` keyed as ``explain:results`` (``ex7_faults.<key>``), the contract of
    ``report.recompute.SELF_RECOMPUTING``; a missing stored table recomputes nothing and is no problem here
    (``STORED_TABLES`` fails it on its own)."""
    import json

    import pandas as pd

    from probecommit.studies.paper_values import value

    insertion = folder.parent / "insertion"
    ins = json.loads((insertion / "results.json").read_text())["results"]
    b = ins["setup"]["bootstrap"]
    boot = dict(resamples=int(b["resamples"]), seed=int(b["seed"]))
    values: dict[str, Any] = {}
    sources: dict[str, str] = {}
    faults = insertion / "faults_episodes.parquet"
    if faults.is_file():
        episodes = pd.read_parquet(faults)
        kmax = int(episodes["k"].max())
        for key, v in ex7_faults.signature_keys(episodes, kmax, boot).items():
            values[f"ex7_faults.signature.{key}"], sources[f"ex7_faults.signature.{key}"] = v, faults.name
    if (folder / ex7_faults.STORED).is_file():
        rows = pd.read_parquet(folder / ex7_faults.STORED)
        for fault, part in rows.groupby("fault", sort=False):
            keys = ex7_faults.surprise_keys(part, boot)
            keys["density_equals_table"] = ex7_faults.equals_table(keys, ins["table_faults"], str(fault))
            for key, v in keys.items():
                values[f"ex7_faults.surprise.{fault}.{key}"] = v
                sources[f"ex7_faults.surprise.{fault}.{key}"] = ex7_faults.STORED
    if (folder / ex7_robust.STORED_DEV).is_file():
        dev = pd.read_parquet(folder / ex7_robust.STORED_DEV)
        keys = ex7_robust.dev_draw_keys(dev, value("T42-robust-chosen.mixture"), ins["robust"]["chosen"]["mixture"])
        for key, v in keys.items():
            values[f"ex7_robust.dev_draws.mixture.{key}"] = v
            sources[f"ex7_robust.dev_draws.mixture.{key}"] = ex7_robust.STORED_DEV
    if (folder / ex7_robust.STORED_HARNESS).is_file():
        for key, v in ex7_robust.harness_draw_keys(pd.read_parquet(folder / ex7_robust.STORED_HARNESS)).items():
            values[f"ex7_robust.harness_draws.mixture.{key}"] = v
            sources[f"ex7_robust.harness_draws.mixture.{key}"] = ex7_robust.STORED_HARNESS
    return values, sources, []
