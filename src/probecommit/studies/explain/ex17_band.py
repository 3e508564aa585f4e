"""What T36's k = 1 AUC asks of the cover schedule's first tap (E127; docs/decisions.md, "ex17").

Why: at k = 1 every cover-schedule trajectory has tapped only -12 mm against the prior, so its running-max
surprise is, up to the reading's noise, whether that tap read the pocket; for a binary score the AUC is
0.5 + (TPR - FPR) / 2. The paper's 0.85 with 50 escapes then needs at least 0.70 x 50 pocket-first escapes, and
the model-consistent pocket readers are covered at k = 1 by construction, so they must come from the misread
band beside -12 mm (pocket in the simulator, top in the model): a share of the band's trajectories that must
still be escaped at k = 5. The band's probability is exact (``ex14_escape.p_band``); the share our draws give
is read from E106's stored rows (five draws under the paper's schedule) joined to their truths.
"""

from __future__ import annotations

from typing import Any, Iterable, Sequence

import numpy as np
import pandas as pd

#: The stored rows (one per trajectory of every draw).
STORED = "ex17_band_rows.parquet"
#: The band's inputs, stored on every row (a closed form of the runs' config).
BAND_COLUMNS = ("first_tap", "x_low", "x_high", "c_low", "c_high", "sim_offset")


def band_rows(surprise_rows: pd.DataFrame, instances: Iterable[pd.DataFrame], inputs: dict[str, float]) -> pd.DataFrame:
    """E106's rows (``draw``, ``instance_id``, ``repeat``, ``escaped_final``, ``first_tap_pocket``) with whether
    each truth lies in the first tap's misread band, and the band's inputs."""
    from probecommit.studies.explain.ex14_escape import in_band
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM, half_gap

    truths = pd.concat([i[["instance_id", "true_x_hole", "true_c"]] for i in instances], ignore_index=True)
    truths = truths.astype({"instance_id": str}).drop_duplicates("instance_id")
    cols = ["draw", "instance_id", "repeat", "escaped_final", "first_tap_pocket"]
    rows = surprise_rows[cols].astype({"instance_id": str}).merge(truths, on="instance_id", how="left", validate="many_to_one")
    band = in_band(np.full(len(rows), inputs["first_tap"]), rows["true_x_hole"].to_numpy(float),
                   half_gap(rows["true_c"].to_numpy(float)), -TIP_RADIUS_MM, inputs["sim_offset"])
    return rows[cols].assign(in_band=np.asarray(band, bool), **inputs)


def p_pocket(u: float, x_box: tuple[float, float], c_box: tuple[float, float], offset: float,
             grid: int = 200_001) -> float:
    """P(a tap at ``u`` reads the pocket in the simulator: ``|u - x| < hg(c) + offset``) for ``x ~ U(x_box)``,
    ``c ~ U(c_box)`` (a midpoint grid over ``c``, as ``ex14_escape.p_band``)."""
    from probecommit.tasks.insertion.model import half_gap

    c = c_box[0] + (np.arange(grid) + 0.5) / grid * (c_box[1] - c_box[0])
    reach = half_gap(c) + offset
    inside = np.clip(np.minimum(u + reach, x_box[1]) - np.maximum(u - reach, x_box[0]), 0.0, None)
    return float(inside.mean() / (x_box[1] - x_box[0]))


def implied_share(p_band: float, n: int, n_escaped: float, auc: float) -> float:
    """The least share of band trajectories escaped at the final budget that a binary first-reading AUC of ``auc``
    with ``n_escaped`` escapes of ``n`` needs (FPR >= 0): ``(2 auc - 1) n_escaped / (n p_band)``."""
    return float((2.0 * auc - 1.0) * n_escaped / (n * p_band))


def keys(rows: pd.DataFrame, n: int, n_escaped: float, auc: float, draws: Sequence[str]) -> dict[str, Any]:
    """E127's keys: the exact P(band) and P(pocket) of the first tap, the band trajectories a draw of ``n`` expects,
    the paper's implied share, and per draw the band count, its escaped share and the pocket-first share of
    escapes; min and max of the share over the draws."""
    from probecommit.studies.explain.ex14_escape import p_band
    from probecommit.tasks.insertion.model import TIP_RADIUS_MM, half_gap

    b = rows.iloc[0]
    box = (float(b["x_low"]), float(b["x_high"])), (float(b["c_low"]), float(b["c_high"]))
    pb = p_band([float(b["first_tap"])], *box, half_gap, -TIP_RADIUS_MM, float(b["sim_offset"]))
    pocket = p_pocket(float(b["first_tap"]), *box, float(b["sim_offset"]))
    out: dict[str, Any] = {"p_band": pb, "p_pocket": pocket, "expected_band": float(n * pb),
                           "implied_share": implied_share(pb, n, n_escaped, auc)}
    shares = []
    for draw in [d for d in draws if d in set(rows["draw"])]:
        part = rows[rows["draw"] == draw]
        band, esc = part["in_band"].to_numpy(bool), part["escaped_final"].to_numpy(bool)
        out[f"{draw}.n_band"], out[f"{draw}.n_band_escaped"] = int(band.sum()), int((band & esc).sum())
        out[f"{draw}.band_escaped_share"] = float(esc[band].mean()) if band.any() else float("nan")
        out[f"{draw}.escapes_in_band"] = float(band[esc].mean()) if esc.any() else float("nan")
        shares.append(out[f"{draw}.band_escaped_share"])
    finite = [s for s in shares if np.isfinite(s)]
    out["draws"] = len(shares)
    out["share.min"] = min(finite) if finite else float("nan")
    out["share.max"] = max(finite) if finite else float("nan")
    return out
