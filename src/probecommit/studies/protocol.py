"""The insertion study's frozen protocol (configs/paper/insertion.yaml) and its runs."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from probecommit.runner.config import ConfigError, StudyConfig, parse_config
from probecommit.store.yamlsafe import load_yaml

DEFAULT_PROTOCOL = Path(__file__).resolve().parents[3] / "configs" / "paper" / "insertion.yaml"


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class InstanceSet(_Strict):
    count: int = Field(ge=1)
    sampling: Literal["uniform", "lhs"] = "uniform"
    seed: int = Field(ge=0)


class Bootstrap(_Strict):
    resamples: int = Field(2000, ge=10)
    seed: int = 0


class Faults(_Strict):
    noise_factor: float = Field(4.0, gt=0)
    prior_half_width: float = Field(12.0, gt=0)
    particles: int = Field(128, ge=1)
    frame_offset: float = 1.0
    temperature: float = Field(4.0, ge=1)
    seed_offset: int = 1


class Robust(_Strict):
    temperatures: list[float]
    epsilons: list[float]
    rejuvenation: list[float]
    mixture_range: tuple[float, float]


class Quick(_Strict):
    instances: int = 6
    development: int = 4
    particles: int = 256
    resamples: int = 200
    resplits: int = 3
    cover_subsets: int = 6


class Protocol(_Strict):
    """Everything the insertion reproduction reads; see configs/paper/insertion.yaml."""

    seed: int
    repeats: int = Field(4, ge=1)
    particles: int = Field(1024, ge=1)
    nu: float = Field(0.8, gt=0, le=1)
    engine: str = "mujoco"
    sigma: float = Field(0.5, gt=0)
    noise_sigma: float = Field(0.5, ge=0)
    alpha: float = Field(0.2, gt=0, lt=1)
    bootstrap: Bootstrap
    instances: dict[str, InstanceSet]
    budgets: dict[str, int]
    cover_schedule: list[float]
    delta: float
    scan: dict[str, float]
    faults: Faults
    robust: Robust
    resplits: dict[str, int]
    quick: Quick

    def quick_version(self) -> "Protocol":
        """The same protocol, scaled down for a fast end-to-end check."""
        q = self.quick
        data = self.model_dump(mode="json")
        for name, inst in data["instances"].items():
            inst["count"] = q.development if name == "development" else q.instances
        data["particles"] = q.particles
        data["bootstrap"]["resamples"] = q.resamples
        data["resplits"]["count"] = q.resplits
        data["faults"]["particles"] = min(self.faults.particles, q.particles // 2)
        return Protocol.model_validate(data)

    def run_config(
        self,
        name: str,
        instance_set: str,
        split: str,
        schedule: str,
        *,
        boundary: str = "deployed",
        methods: tuple[str, ...] = ("probe_robust",),
        seed_offset: int = 0,
        noise_factor: float = 1.0,
        truth_half_width: float | None = None,
        unit_instances: int = 8,
    ) -> StudyConfig:
        """The StudyConfig of one run of the protocol."""
        inst = self.instances[instance_set]
        instances: dict[str, Any] = {"split": split, "count": inst.count, "sampling": inst.sampling, "seed": inst.seed}
        if truth_half_width is not None:
            instances["truth_low"] = (-truth_half_width, 0.7)
            instances["truth_high"] = (truth_half_width, 1.3)
        cover = schedule == "cover"
        return parse_config(
            {
                "name": name,
                "seed": self.seed + seed_offset,
                "repeats": self.repeats,
                "instances": instances,
                "probes": {
                    "schedule": list(self.cover_schedule) if cover else "random",
                    "budget": self.budgets["cover" if cover else "random"],
                },
                "model": {"boundary": boundary, "delta": self.delta, "sigma": self.sigma},
                "belief": {"particles": self.particles, "nu": self.nu},
                "simulator": {"engine": self.engine, "noise_sigma": self.noise_sigma * noise_factor},
                "methods": list(methods),
                "unit_instances": unit_instances,
            }
        )


def load_protocol(path: str | Path = DEFAULT_PROTOCOL) -> Protocol:
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"protocol file not found: {path}")
    try:
        return Protocol.model_validate(load_yaml(path.read_bytes(), str(path)))
    except Exception as exc:  # pydantic's message names the field
        raise ConfigError(f"{path}: {str(exc).splitlines()[0]} — {str(exc).splitlines()[1].strip() if len(str(exc).splitlines()) > 1 else ''}") from None
