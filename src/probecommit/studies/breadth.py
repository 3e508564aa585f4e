"""Table II (``tab:breadth``: every family, blind against probed) for the continuous-loss families.

For each family's run directory (or frozen config, run here) this computes

* the mean miss of Blind-Bayes (k = 0), Blind-Robust (k = 0) and Probe-Robust(k), each
  with a cluster-bootstrap interval over instances (repeats kept together);
* the paired reduction ``Blind-Bayes - Probe-Robust(k)`` on identical episodes (same
  instance and seed), the paper's Delta column in every row (0.820 - 0.234 = 0.586 for
  insertion), with a paired cluster bootstrap over instances and a sign-flip p-value;
  positive = probing reduced the miss. ``Blind-Robust - Probe-Robust(k)`` (only the
  information changes) is kept as the extra column ``paired_robust``;
* the miss-versus-budget curve as a table, and a figure (3.5 in wide, PNG + PDF).

Frozen configs live in ``configs/paper/<family>.yaml``; :func:`run_breadth` runs them
through :func:`probecommit.runner.study.run_study`. The paper's own values are in
:mod:`probecommit.studies.paper_values` (``tab:breadth.*``), for side-by-side reporting only.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from probecommit.audit.stats import DEFAULT_RESAMPLES, cluster_bootstrap_mean, paired_bootstrap
from probecommit.store.safefile import write_with

#: Families this study covers, in table order.
BREADTH_FAMILIES = ("push1d", "push2d", "push2d_pybullet", "darts", "hinge", "shuffleboard", "grasp")
#: Probe-Robust budget of each family's Table II column (paper: five probes, two for
#: shuffleboard, eight for grasp).
FAMILY_K = {"shuffleboard": 2, "grasp": 8}
#: Unit of a family's miss (m unless listed); grasp reports success on its feasible subset.
FAMILY_UNIT = {"hinge": "rad", "grasp": "success"}
#: Families whose Table II cell is "mean / P90".
P90_FAMILIES = ("shuffleboard",)
#: Families reported as success on the feasible subset (binary loss; higher is better).
SUCCESS_FAMILIES = ("grasp",)
#: Frozen paper configs.
#: The frozen paper configs shipped with the package (``configs/paper`` in the repository).
PAPER_CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs" / "paper"
#: Quick mode (CI): instances kept per family and particles.
QUICK = {"instances": 2, "repeats": 2, "particles": 128, "blind_prior_samples": 500}

PAIR_KEYS = ("instance_id", "repeat")


def _ok(episodes: pd.DataFrame) -> pd.DataFrame:
    if "status" in episodes:
        episodes = episodes[episodes["status"] == "ok"]
    return episodes


def arm(episodes: pd.DataFrame, method: str, k: int) -> pd.DataFrame:
    """Rows of one method at one budget (successful episodes only)."""
    ep = _ok(episodes)
    return ep[(ep["method"] == method) & (ep["k"] == k)]


def _mean(rows: pd.DataFrame, resamples: int, seed: int) -> dict[str, float]:
    if rows.empty:
        return {"mean": float("nan"), "lo": float("nan"), "hi": float("nan"), "n": 0, "p90": float("nan")}
    ci = cluster_bootstrap_mean(rows["realized"].to_numpy(float), rows["instance_id"].to_numpy(), resamples=resamples, seed=seed)
    return {"mean": ci.estimate, "lo": ci.lo, "hi": ci.hi, "n": int(len(rows)),
            "p90": float(np.percentile(rows["realized"].to_numpy(float), 90))}


def breadth_row(episodes: pd.DataFrame, family: str = "", k: int = 5, *, resamples: int = DEFAULT_RESAMPLES,
                seed: int = 0) -> dict[str, Any]:
    """One Table II row from an episode table.

    Args:
        episodes: Episode table with ``instance_id, repeat, k, method, realized`` (and
            optionally ``status``).
        family: Label of the row.
        k: Probe budget of the Probe-Robust column.
        resamples, seed: Cluster bootstrap settings.

    Returns:
        ``family, k, n_instances``; ``blind_bayes``, ``blind_robust``, ``probe_robust``
        mean miss (with ``_lo``/``_hi``); ``paired`` = mean of Blind-Bayes minus
        Probe-Robust(k) over paired (instance, repeat) episodes with ``paired_lo``,
        ``paired_hi``, ``paired_p`` (sign-flip) and ``n_pairs``; ``paired_robust`` the same for
        Blind-Robust minus Probe-Robust(k) (NaN when an arm is missing).
    """
    row: dict[str, Any] = {"family": family, "k": int(k)}
    arms = {"blind_bayes": arm(episodes, "blind_bayes", 0), "blind_robust": arm(episodes, "blind_robust", 0),
            "probe_robust": arm(episodes, "probe_robust", k)}
    row["n_instances"] = int(_ok(episodes)["instance_id"].nunique())
    for name, rows in arms.items():
        stat = _mean(rows, resamples, seed)
        row[name], row[f"{name}_lo"], row[f"{name}_hi"] = stat["mean"], stat["lo"], stat["hi"]
        row[f"{name}_p90"] = stat["p90"]
        row[f"n_{name}"] = stat["n"]
    for name, base_arm in (("paired", "blind_bayes"), ("paired_robust", "blind_robust")):
        row.update({name: float("nan"), f"{name}_lo": float("nan"), f"{name}_hi": float("nan"),
                    f"{name}_p": float("nan"), f"n_pairs_{name}": 0})
        base, treat = arms[base_arm], arms["probe_robust"]
        if len(base) and len(treat):
            # treatment = the blind arm, baseline = Probe-Robust(k): the difference is the reduction.
            res = paired_bootstrap(treat, base, "realized", keys=PAIR_KEYS, resamples=resamples, seed=seed)
            row.update({name: res.difference.estimate, f"{name}_lo": res.difference.lo,
                        f"{name}_hi": res.difference.hi, f"{name}_p": res.p_sign_flip, f"n_pairs_{name}": res.n_pairs})
    row["paired_p"], row["n_pairs"] = row.pop("paired_p"), row.pop("n_pairs_paired")
    return row


def budget_curve(episodes: pd.DataFrame, family: str = "", *, resamples: int = DEFAULT_RESAMPLES,
                 seed: int = 0) -> pd.DataFrame:
    """Mean miss versus budget: ``family, method, k, mean, lo, hi, n`` (blind methods at k = 0)."""
    ep = _ok(episodes)
    rows = []
    for (method, k), group in ep.groupby(["method", "k"], sort=True):
        if method not in ("blind_bayes", "blind_robust", "probe_robust"):
            continue
        rows.append({"family": family, "method": method, "k": int(k), **_mean(group, resamples, seed)})
    order = {"blind_bayes": 0, "blind_robust": 1, "probe_robust": 2}
    out = pd.DataFrame(rows, columns=["family", "method", "k", "mean", "lo", "hi", "n"])
    return out.sort_values(["method", "k"], key=lambda s: s.map(order) if s.name == "method" else s).reset_index(drop=True)


def read_episodes(run_dir: str | Path) -> pd.DataFrame:
    """The episode table of a run directory."""
    from probecommit.store.rundir import RunDir

    return pd.read_parquet(RunDir(run_dir).table_path("episodes"))


def as_success(row: dict[str, Any]) -> dict[str, Any]:
    """A failure row as success (``1 - failure``; intervals swap ends); the paired reduction in
    failure is already the gain in success. P90 of a 0/1 outcome says nothing and is dropped."""
    out = dict(row, metric="success")
    for name in ("blind_bayes", "blind_robust", "probe_robust"):
        out[name], out[f"{name}_lo"], out[f"{name}_hi"] = 1 - row[name], 1 - row[f"{name}_hi"], 1 - row[f"{name}_lo"]
        out[f"{name}_p90"] = float("nan")
    return out


def truth_sign_flip(episodes: pd.DataFrame, truth_of: Mapping[str, str], k: int) -> dict[str, Any]:
    """Per-truth success of Probe-Robust(k) minus Blind-Bayes, and the exact sign-flip test over truths.

    Args:
        episodes: Episodes of the feasible instances (binary ``realized`` failure).
        truth_of: ``instance_id -> truth label`` (instances of one truth pooled).
        k: Probe budget.

    Returns:
        Counts of truths that improve, tie (difference exactly zero) and worsen, the
        improvements' range, and the two-sided exact sign-flip p-value (ties contribute
        nothing under any sign; with ``n`` untied truths all of one sign, ``p = 2 / 2^n``).
    """
    from probecommit.audit.stats import sign_flip_test

    ep = _ok(episodes).assign(truth=lambda d: d["instance_id"].map(truth_of))
    success = lambda rows: 1.0 - rows.groupby("truth")["realized"].mean()  # noqa: E731
    diff = (success(arm(ep, "probe_robust", k)) - success(arm(ep, "blind_bayes", 0))).dropna()
    up, down = diff[diff > 0], diff[diff < 0]
    return {"n_truths": int(len(diff)), "n_improve": int(len(up)), "n_tie": int((diff == 0).sum()),
            "n_worse": int(len(down)), "improve_min": float(up.min()) if len(up) else float("nan"),
            "improve_max": float(up.max()) if len(up) else float("nan"),
            "p_sign_flip": float(sign_flip_test(diff.to_numpy())),
            "differences": {str(t): float(v) for t, v in diff.items()}}


#: A success family's rows its per-truth sign count reads (``truth_rows``), stored beside Table II's episodes.
SIGN_FLIP_ROWS = "sign_flip_rows.parquet"


def truth_rows(config: Any, run_dir: str | Path) -> pd.DataFrame:
    """A run's episodes (the columns the sign count reads) with each instance's ``feasible`` and ``truth`` label:
    what :func:`sign_flip_summary` reads, in the run directory or stored in a publication."""
    run_dir = Path(run_dir)
    feasible = feasible_instances(config, run_dir)
    episodes = pd.read_parquet(run_dir / "episodes.parquet")
    instances = pd.read_parquet(run_dir / "instances.parquet")
    truth_cols = [c for c in instances.columns if c.startswith("true_")]
    truth_of = dict(zip(instances["instance_id"], instances[truth_cols].astype(str).agg(",".join, axis=1)))
    rows = episodes[["instance_id", "repeat", "method", "k", "status", "realized"]].reset_index(drop=True)
    ids = pd.DataFrame({"instance_id": list(feasible), "feasible": list(feasible.values()),
                        "truth": [truth_of[i] for i in feasible]})
    return rows.merge(ids, on="instance_id", how="left", sort=False)


def sign_flip_summary(rows: pd.DataFrame, k: int) -> dict[str, Any]:
    """:func:`truth_sign_flip` over the feasible truths of :func:`truth_rows`, with the feasible and total instance
    counts (one function for the breadth study, the explain step's model-exact grasp and verify)."""
    per_instance = rows.drop_duplicates("instance_id")
    feasible = dict(zip(per_instance["instance_id"], per_instance["feasible"].astype(bool)))
    episodes = rows[rows["instance_id"].map(feasible).fillna(False).astype(bool)]
    out = truth_sign_flip(episodes, dict(zip(per_instance["instance_id"], per_instance["truth"])), k)
    return {**out, "n_feasible": int(sum(feasible.values())), "n_instances": len(feasible)}


def breadth_table(runs: Mapping[str, str | Path | pd.DataFrame], k: int = 5, *, resamples: int = DEFAULT_RESAMPLES,
                  seed: int = 0) -> pd.DataFrame:
    """Table II rows for ``{family: run directory or episode table}``, in the given order."""
    rows = []
    for family, src in runs.items():
        episodes = src if isinstance(src, pd.DataFrame) else read_episodes(src)
        rows.append(breadth_row(episodes, family, FAMILY_K.get(family, k), resamples=resamples, seed=seed))
    return pd.DataFrame(rows)


def budget_curves(runs: Mapping[str, str | Path | pd.DataFrame], *, resamples: int = DEFAULT_RESAMPLES,
                  seed: int = 0) -> pd.DataFrame:
    """Miss-versus-budget table of every family."""
    frames = []
    for family, src in runs.items():
        episodes = src if isinstance(src, pd.DataFrame) else read_episodes(src)
        frames.append(budget_curve(episodes, family, resamples=resamples, seed=seed))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def _fmt(v: Any, digits: int = 3) -> str:
    return "--" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f"{v:.{digits}f}"


def _cell(r: Mapping[str, Any], name: str, p90: bool) -> str:
    value = _fmt(r.get(name))
    if p90 and value != "--":
        value += f" / {_fmt(r.get(f'{name}_p90'))}"
    return value


def _paired_cell(r: Mapping[str, Any], name: str) -> str:
    v = r.get(name)
    if v is None or not np.isfinite(v):
        return "--"
    return f"{v:.3f} [{r[f'{name}_lo']:.3f}, {r[f'{name}_hi']:.3f}]"


def _paper_row(family: str) -> dict[str, Any] | None:
    from probecommit.studies.paper_values import PRINTED as PAPER

    cells = {k.rsplit(".", 1)[1]: v for k, v in PAPER.items() if k.startswith(f"tab:breadth.{family}.")}
    return cells or None


def breadth_markdown(table: pd.DataFrame, paper: bool = True) -> str:
    """Markdown Table II, ours next to the paper's (``paper``); Delta = Blind-Bayes - Probe-Robust(k)."""
    head = ("| family | unit | Blind-Bayes | Blind-Robust | Probe-Robust(k) | paired Delta = Blind-Bayes - Probe-Robust "
            "[95%] | Blind-Robust - Probe-Robust [95%] |")
    lines = [head, "|---|---|---|---|---|---|---|"]
    for _, r in table.iterrows():
        family = r["family"]
        p90 = family in P90_FAMILIES
        unit = FAMILY_UNIT.get(family, "m") + (" (mean / P90)" if p90 else "")
        if family == "insertion_A":
            unit = "failure"
        lines.append(f"| {family} (ours, k={r['k']}) | {unit} | {_cell(r, 'blind_bayes', p90)} | "
                     f"{_cell(r, 'blind_robust', p90)} | {_cell(r, 'probe_robust', p90)} | {_paired_cell(r, 'paired')} | "
                     f"{_paired_cell(r, 'paired_robust')} |")
        p = _paper_row(family) if paper else None
        if p:
            delta = f"{p['delta']} [{p['delta_lo']}, {p['delta_hi']}]" if "delta" in p else p.get("change_percent", "--")
            delta = f"{delta} %" if "delta" not in p and delta != "--" else delta
            cell = lambda n: p.get(n, "--") + (f" / {p[n + '_p90']}" if p90 and n + "_p90" in p else "")  # noqa: E731
            lines.append(f"| {family} (paper, k={FAMILY_K.get(family, 5)}) | {unit} | {cell('blind_bayes')} | "
                         f"{cell('blind_robust')} | {cell('probe_robust')} | {delta} | -- |")
    return "\n".join(lines) + "\n"


LABELS = {"blind_bayes": "Blind-Bayes", "blind_robust": "Blind-Robust", "probe_robust": "Probe-Robust(k)"}


def plot_budget_curves(curves: pd.DataFrame, path: str | Path) -> list[Path]:
    """Miss versus budget, one panel per family; saves ``<path>.png`` and ``<path>.pdf``.

    3.5 in wide, every font at least 7 pt; blind methods are drawn as markers at k = 0,
    Probe-Robust as a line through Blind-Robust's k = 0 point (the same risk functional).
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    families = list(dict.fromkeys(curves["family"]))
    n = max(len(families), 1)
    ncols = min(n, 4)
    nrows = -(-n // ncols)
    width = 3.5 if ncols <= 2 else 7.16
    with plt.rc_context({"font.size": 7, "axes.titlesize": 7, "axes.labelsize": 7, "xtick.labelsize": 7,
                         "ytick.labelsize": 7, "legend.fontsize": 7}):
        fig, axes = plt.subplots(nrows, ncols, figsize=(width, 1.75 * nrows + 0.3), squeeze=False)
        for ax in axes.flat[n:]:
            ax.set_visible(False)
        for ax, fam in zip(axes.flat, families):
            c = curves[curves["family"] == fam]
            br = c[c["method"] == "blind_robust"]
            pr = c[c["method"] == "probe_robust"]
            line = pd.concat([br, pr]).sort_values("k")
            ax.errorbar(line["k"], line["mean"], yerr=[line["mean"] - line["lo"], line["hi"] - line["mean"]],
                        marker="o", ms=3, lw=1, capsize=2, color="C0", label="Blind-/Probe-Robust")
            bb = c[c["method"] == "blind_bayes"]
            if len(bb):
                ax.errorbar(bb["k"] - 0.15, bb["mean"], yerr=[bb["mean"] - bb["lo"], bb["hi"] - bb["mean"]],
                            marker="s", ms=3, lw=0, elinewidth=1, capsize=2, color="C1", label="Blind-Bayes")
            ax.set_title(fam)
            ax.set_xlabel("probes k")
            ax.set_xticks(sorted(set(c["k"])))
            ax.set_ylim(bottom=0)
            unit = FAMILY_UNIT.get(fam, "m")
            ax.set_ylabel("failure (all truths)" if unit == "success" else f"mean miss ({unit})")
        handles, labels = axes[0][0].get_legend_handles_labels()
        fig.legend(handles, labels, frameon=False, loc="upper center", ncol=2, handlelength=1.2)
        fig.tight_layout(pad=0.3, rect=(0, 0, 1, 1 - 0.3 / (1.75 * nrows + 0.3)))
        stem = Path(path).with_suffix("")
        out = [stem.with_suffix(".png"), stem.with_suffix(".pdf")]
        for p in out:
            # No creation date in the PDF: the same figure is the same bytes (frozen results are hashed).
            write_with(p, lambda buf, p=p: fig.savefig(buf, format=p.suffix[1:], dpi=300,
                                                      metadata={"CreationDate": None} if p.suffix == ".pdf" else None))
        plt.close(fig)
    return out


def quick_config(config: Any) -> Any:
    """A small version of a frozen config for CI: first instances, few repeats and particles."""
    from probecommit.runner.config import config_data, parse_config

    data = config_data(config)
    inst = data["instances"]
    truths = inst["truths"][: QUICK["instances"]] if inst.get("truths") else None
    contexts = inst["contexts"][:1] if inst.get("contexts") else None
    if truths is not None:
        inst["truths"] = truths
    if contexts is not None:
        inst["contexts"] = contexts
    if truths is None:
        inst["count"] = QUICK["instances"]
    data["repeats"] = QUICK["repeats"]
    data["belief"]["particles"] = QUICK["particles"]
    data["blind_prior_samples"] = QUICK["blind_prior_samples"]
    data["name"] = f"{data['name']}-quick"
    return parse_config(data)


def paper_config(family: str, config_dir: str | Path = PAPER_CONFIG_DIR) -> Any:
    """The frozen study config of ``family``."""
    from probecommit.runner.config import load_config

    return load_config(Path(config_dir) / f"{family}.yaml")


def run_breadth(families: Iterable[str] = BREADTH_FAMILIES, out_dir: str | Path = "runs/breadth", quick: bool = False,
                *, k: int = 5, workers: int = 1, resamples: int = DEFAULT_RESAMPLES, seed: int = 0,
                config_dir: str | Path = PAPER_CONFIG_DIR) -> pd.DataFrame:
    """Run each family's frozen config (resuming finished runs) and return its Table II rows.

    Args:
        families: Family names with a ``configs/paper/<family>.yaml``.
        out_dir: Parent of the run directories (``<out_dir>/<family>[-quick]``).
        quick: Two truths x one target, two seeds, 128 particles (CI).
        k: Probe-Robust budget of the table.
        workers: Local worker processes per run.
        resamples, seed: Cluster bootstrap settings.
    """
    from probecommit.runner.aside import in_own_process

    out_dir = Path(out_dir)
    runs: dict[str, pd.DataFrame] = {}
    for family in families:
        config = paper_config(family, config_dir)
        if quick:
            config = quick_config(config)
        # Each family's run in a process of its own: its units' losses and beliefs, and its engine answers, leave
        # with it (the target's process held 521 MB by darts, the fifth family; issue 42, target 4).
        episodes = in_own_process(_run_episodes, family, config_dir, quick, out_dir / config.name, workers)
        runs[family] = episodes
        if family in SUCCESS_FAMILIES:
            runs[family] = feasible_episodes(config, out_dir / config.name, episodes)
    table = breadth_table(runs, k, resamples=resamples, seed=seed)
    rows = [as_success(r) if r["family"] in SUCCESS_FAMILIES else r for r in table.to_dict("records")]
    return pd.DataFrame(rows)


def _run_episodes(family: str, config_dir: str | Path, quick: bool, run_dir: Path, workers: int) -> pd.DataFrame:
    """``run_study``'s episodes of the family's config (``run_breadth``, in a process of its own: a config is
    built there, as it does not pickle)."""
    from probecommit.runner.study import run_study

    config = paper_config(family, config_dir)
    return run_study(quick_config(config) if quick else config, run_dir, workers=workers).episodes


def feasible_instances(config: Any, run_dir: str | Path) -> dict[str, bool]:
    """``instance_id -> feasible``: whether some grid action succeeds for the instance's truth in
    the run's engine (only actions near the truth's success window are tried)."""
    from probecommit.runner.build import build_model, build_simulator
    from probecommit.store.rundir import RunDir

    model, sim = build_model(config), build_simulator(config)
    instances = pd.read_parquet(RunDir(run_dir).table_path("instances"))
    truths = instances[[f"true_{n}" for n in model.latent_names]].to_numpy(float)
    return {iid: bool(sim.feasible(theta, model.action_grid)) for iid, theta in zip(instances["instance_id"], truths)}


def feasible_episodes(config: Any, run_dir: str | Path, episodes: pd.DataFrame) -> pd.DataFrame:
    """The episodes of feasible instances only (grasp's Table II reports success on them)."""
    feasible = feasible_instances(config, run_dir)
    out = episodes[episodes["instance_id"].map(feasible).fillna(False).astype(bool)]
    out.attrs["feasible"] = feasible
    return out
