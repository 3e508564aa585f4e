"""2-D push (MuJoCo) under MuJoCo's default, pyramidal friction cone (E50).

Why: the paper's 2-D push row is the one where probing barely helps, where its 1-D push
(same latents, probe and sigma) gains most of the miss; ours gains most on both. Our MuJoCo
scene sets the elliptic cone because the default pyramidal one makes friction depend on the
sliding direction, which no isotropic model fitted along +x represents; a scene left at
MuJoCo's defaults, as the paper's may have been (it does not say), has that error at the
commits' bearings (-20 and +30 degrees) and none along the probes' (+x). If the probes read the
same under both cones (checked: the premise), the beliefs and every executor's action are the
frozen study's, so the study under the pyramidal cone is the stored actions re-executed in that
scene: the frozen push2d run and its prior-width sweep, each Table II row recomputed, and the
single-width rule asked again (docs/decisions.md, "ex4").
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from probecommit.studies.breadth import breadth_row
from probecommit.studies.explain.ex4_breadth import single_width

#: The stored rows the keys are computed from (``explain/results/``).
STORED = "ex4_cone_rows.parquet"
#: Premise: the largest difference of a noise-free probe reading between the cones (m): 1 % of sigma.
PREMISE_M = 0.0005
#: The arms a Table II row reads: the blind ones at k = 0, Probe-Robust at the row's budget.
ARMS = (("blind_bayes", 0), ("blind_robust", 0), ("probe_robust", 5))
PULSES = (1.0, 2.0, 3.0)


def Scene(cone: str) -> Any:
    """The frozen push2d MuJoCo scene with friction cone ``cone``: noise-free rests, cached per query."""
    from probecommit.tasks.push2d import sim_mujoco

    class ConeScene(sim_mujoco.MujocoPush2DSimulator):
        def __init__(self) -> None:
            super().__init__(0.0)
            self.answers: dict[tuple[float, ...], np.ndarray] = {}

        def _compile(self, mu: float, m: float, k_d: float) -> tuple[Any, Any]:
            xml = sim_mujoco.scene_xml(mu, m, k_d)
            if 'cone="elliptic"' not in xml:
                raise RuntimeError("the push2d scene no longer names its cone; E50 cannot switch it")
            model = self._mj.MjModel.from_xml_string(xml.replace('cone="elliptic"', f'cone="{cone}"'))
            return model, self._mj.MjData(model)

        def rest_of(self, theta: tuple[float, ...], impulse: tuple[float, ...]) -> np.ndarray:
            key = (*map(float, theta), *map(float, impulse))
            if key not in self.answers:
                self.answers[key] = self.rest(*key)
            return self.answers[key]

    return ConeScene()


def reexecuted(run_dir: Path, scene: Any, scale: float) -> pd.DataFrame:
    """The run's Table II rows (``ARMS``) with ``realized`` the miss of the stored action in ``scene``."""
    ep = pd.read_parquet(run_dir / "episodes.parquet")
    ins = pd.read_parquet(run_dir / "instances.parquet").set_index("instance_id")
    keep = np.zeros(len(ep), bool)
    for method, k in ARMS:
        keep |= (ep["method"] == method).to_numpy() & (ep["k"] == k).to_numpy()
    rows = ep.loc[keep & (ep["status"] == "ok").to_numpy(), ["instance_id", "repeat", "k", "method", "action_0",
                                                              "action_1", "realized", "status"]].copy()
    misses = []
    for r in rows.itertuples():
        i = ins.loc[r.instance_id]
        rest = scene.rest_of((i.true_mu, i.true_m, i.true_k_d), (r.action_0, r.action_1))
        misses.append(float(np.hypot(rest[0] - i.ctx_target_x, rest[1] - i.ctx_target_y)))
    return rows.rename(columns={"realized": "realized_elliptic"}).assign(realized=misses, scale=float(scale))


def premise(run_dirs: list[Path], scene: Any, reference: Any) -> float:
    """The largest difference (m) of a noise-free probe reading between the two scenes over every truth and pulse."""
    worst = 0.0
    for run_dir in run_dirs:
        ins = pd.read_parquet(run_dir / "instances.parquet")
        for t in ins[["true_mu", "true_m", "true_k_d"]].drop_duplicates().itertuples(index=False):
            for u in PULSES:
                worst = max(worst, float(np.max(np.abs(scene.rest_of(tuple(t), (u, 0.0))
                                                       - reference.rest_of(tuple(t), (u, 0.0))))))
    return worst


def keys(stored: pd.DataFrame, premise_m: float, boot: dict[str, Any]) -> dict[str, Any]:
    """Keys of ``explain:results.ex4_cone`` from the re-executed rows (``STORED``) and the premise's measure."""
    from probecommit.studies.explain.breadth import paper_cells

    out: dict[str, Any] = {"premise_max_probe_difference_m": premise_m, "premise_holds": float(premise_m <= PREMISE_M)}
    rows = {}
    for s, part in stored.groupby("scale", sort=True):
        row = breadth_row(part, "push2d", 5, resamples=boot["resamples"], seed=boot["seed"])
        rows[float(s)] = {f"{c}{x}": float(row[f"{c}{x}"]) for c in ("blind_bayes", "blind_robust", "probe_robust",
                                                                      "paired") for x in ("", "_lo", "_hi")}
        out.update({f"s{float(s):g}.{k}": v for k, v in rows[float(s)].items()})
        out[f"s{float(s):g}.elliptic_probe_robust"] = float(
            part.loc[part["method"] == "probe_robust", "realized_elliptic"].mean())
    out.update(single_width(rows, paper_cells("push2d")))
    return out


def run(root: Path, runs: Path, boot: dict[str, Any], quick: bool) -> tuple[dict[str, Any], pd.DataFrame]:
    """The frozen push2d run and its prior sweep re-executed under the pyramidal cone (quick: the quick sweep's
    push2d runs if any, else nothing)."""
    sweep = sorted((runs / "breadth_prior").glob("push2d_prior*"))
    dirs = {float(p.name.removeprefix("push2d_prior")): p for p in sweep if (p / "episodes.parquet").is_file()}
    frozen = root / "breadth" / "runs" / "push2d"
    if not quick and (frozen / "episodes.parquet").is_file():
        dirs[1.0] = frozen
    if not dirs:
        return {}, pd.DataFrame()
    scene = Scene("pyramidal")
    stored = pd.concat([reexecuted(d, scene, s) for s, d in sorted(dirs.items())], ignore_index=True)
    measured = premise(list(dirs.values()), scene, Scene("elliptic"))
    return keys(stored, measured, boot), stored
