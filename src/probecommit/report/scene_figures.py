"""Paper figures made of scene renders: Fig. 1a (the taps of one episode), Fig. 1c (the peg
at that episode's aim) and Fig. 3 (the scenes of every family), each at its slot's width.

The renders come from :mod:`probecommit.report.scenes` (``scenes.json`` lists them and
what drew each); a scene that could not be rendered is left out and named in the caption.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from probecommit.report.figures import save_figure  # noqa: E402
from probecommit.report.style import COLUMN  # noqa: E402


def _image(folder: Path, name: str) -> np.ndarray:
    from PIL import Image

    with Image.open(folder / name) as im:
        return np.asarray(im.convert("RGB"))


def _scenes(folder: Path) -> dict[str, Any]:
    return json.loads((folder / "scenes.json").read_text())


def fig1_panel(scene_dir: str | Path, which: str, spec: dict[str, Any], path: str | Path) -> Path | None:
    """Fig. 1a (``which="a"``: the taps) or 1c (``"c"``: the peg at the aim), half a column wide.

    ``spec``: ``taps`` [(u mm, read pocket)], ``x_hole``, ``aim`` (mm), as given to the renders.
    Returns None where the render is missing (no GL here).
    """
    scene_dir = Path(scene_dir)
    name = "scene_fig1a_taps.png" if which == "a" else "scene_fig1c_insertion.png"
    if not (scene_dir / name).is_file():
        return None
    fig, ax = plt.subplots(figsize=(COLUMN / 2, COLUMN / 2 * 0.86))
    ax.imshow(_image(scene_dir, name))
    ax.set_axis_off()
    n_pocket = sum(bool(p) for _, p in spec["taps"])
    if which == "a":
        ax.set_title(f"(a) {len(spec['taps'])} taps, {n_pocket} into the pocket", fontsize=7)
        caption = (f"(a) Surface-height probes of one simulated insertion episode (MuJoCo): the tip at each of its "
                   f"{len(spec['taps'])} taps (u = {', '.join(f'{u:+.0f}' for u, _ in spec['taps'])} mm), "
                   f"{n_pocket} reading the pocket; hole at {spec['x_hole']:+.2f} mm.")
    else:
        ax.set_title(f"(c) insertion at the aim {spec['aim']:+.1f} mm", fontsize=7)
        caption = (f"(c) The peg inserted at the episode's fifth aim, {spec['aim']:+.2f} mm, hole at "
                   f"{spec['x_hole']:+.2f} mm (MuJoCo scene, software OpenGL).")
    fig.tight_layout(pad=0.1)
    return save_figure(fig, path, caption=caption)


def fig3_scenes(scene_dir: str | Path, path: str | Path) -> Path | None:
    """Fig. 3: every family's scene, one column wide, each labelled with its engine and renderer."""
    scene_dir = Path(scene_dir)
    listing = _scenes(scene_dir)
    renders = [r for r in listing["renders"] if not r["file"].startswith("scene_fig1")]
    if not renders:
        return None
    ncols = 3
    nrows = -(-len(renders) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(COLUMN, 0.95 * nrows + 0.1), squeeze=False)
    for ax in axes.flat:
        ax.set_axis_off()
    for ax, r in zip(axes.flat, renders):
        ax.imshow(_image(scene_dir, r["file"]))
        engine = "SAPIEN, drawn" if r["engine"].startswith("SAPIEN") else r["engine"]  # not a SAPIEN render: say so
        ax.set_title(f"{r['family']}, {engine}", fontsize=7, pad=2)
    fig.tight_layout(pad=0.15, h_pad=0.4, w_pad=0.2)
    skipped = ", ".join(f"{s['family']} ({s['engine']})" for s in listing.get("skipped", []))
    caption = ("The simulated scenes: MuJoCo rendered through software OpenGL, PyBullet by its TinyRenderer, the SAPIEN "
               "shuffleboard drawn with matplotlib from the scene's own box dimensions (SAPIEN 3 finds no render device "
               "on a CPU; its puck drawn 10x its size). The darts sphere is drawn at 6x its 1 cm radius so that it shows over "
               "its fall. The 1-D push is closed form and has no scene."
               + (f" Not rendered on this machine: {skipped}." if skipped else ""))
    return save_figure(fig, path, caption=caption)
