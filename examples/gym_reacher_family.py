"""A task family whose ground truth is a real Gymnasium MuJoCo environment (Reacher-v5).

The shoulder joint's damping is the unknown physics. A probe holds a small shoulder torque
for 40 steps (0.8 s) and reads how far the arm turned; the commit holds one torque to turn
the arm by a target angle (the context); the loss is the miss in radians.

Gymnasium's Reacher does not take its physics from ``reset(options=...)``, so a 9-line
wrapper (``LatentReacher``) writes the damping into the MuJoCo model there; everything else
is Gymnasium's environment as shipped. Import this module (it registers ``gym_reacher``), then:

    python examples/gym_reacher_family.py        # check_family, a small study and its audit

Needs ``pip install 'probecommit[gym]'`` (gymnasium with its MuJoCo environments).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from probecommit.tasks.adapters.gym import GymProtocol, gym_family
from probecommit.tasks.declare import Context, Latent


class LatentReacher(gym.Wrapper):
    """Reacher-v5 whose shoulder damping is set by ``reset(options={"latents": {"damping": value}})``."""

    def __init__(self) -> None:
        super().__init__(gym.make("Reacher-v5", max_episode_steps=1000))

    def reset(self, *, seed=None, options=None):
        latents = (options or {}).get("latents", {})
        if "damping" in latents:
            self.env.unwrapped.model.dof_damping[0] = latents["damping"]
        return self.env.reset(seed=seed)


def turned(first_obs: np.ndarray, last_obs: np.ndarray, info: dict) -> float:
    """Shoulder angle turned (rad), from the observation's cos and sin of the joint angle."""
    return float(np.arctan2(last_obs[2], last_obs[0]) - np.arctan2(first_obs[2], first_obs[0]))


SPEC = gym_family(
    "gym_reacher",
    protocol=GymProtocol(
        make_env=LatentReacher,
        measure=turned,
        loss=lambda value, target: np.abs(value[..., 0] - target[..., 0]),
        steps=40,
        command=lambda torque: np.array([float(torque[0]), 0.0]),  # shoulder torque, elbow free
    ),
    latents=[Latent("damping", "N m s/rad", 0.25, 4.0, positive=True)],
    probe_grid=[0.01, 0.02],
    action_grid=np.round(np.arange(0.002, 0.0601, 0.001), 6),
    contexts=[Context("target", "rad", 0.3, 1.2)],
    sigma=0.02,
    lattice=9,
    summary={"probe": "held torque / angle turned", "action": "held torque"},
)


def main() -> None:
    import tempfile
    from pathlib import Path

    import probecommit
    from probecommit.audit.pipeline import audit
    from probecommit.runner.config import parse_config
    from probecommit.runner.study import run_study

    report = probecommit.check_family("gym_reacher")
    print(f"check_family: {len(report.passed)} checks passed")
    config = parse_config({"name": "reacher", "task": "gym_reacher", "seed": 1, "repeats": 2,
                           "instances": {"count": 4, "contexts": [[0.5], [1.0]]},
                           "probes": {"schedule": "random", "budget": 2}, "belief": {"particles": 256},
                           "blind_prior_samples": 500})
    with tempfile.TemporaryDirectory() as tmp:
        run_study(config, Path(tmp) / "run")
        print(audit(Path(tmp) / "run", resamples=200).table[["method", "k", "coverage", "escape", "realized",
                                                                "predicted"]].to_string(index=False))


if __name__ == "__main__":
    main()
