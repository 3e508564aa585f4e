"""TaskModelBase: the shared sigma/margin checks and with_margin."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from probecommit.tasks.base import TaskModelBase
from probecommit.tasks.darts.model import DartsModel
from probecommit.tasks.grasp.model import GraspModel
from probecommit.tasks.insertion.model import InsertionModel
from probecommit.tasks.planar_slide.model import PlanarSlideModel
from probecommit.tasks.push1d.model import Push1DModel
from probecommit.tasks.push2d.model import Push2DModel

FAMILIES = [DartsModel, GraspModel, InsertionModel, PlanarSlideModel, Push1DModel, Push2DModel]


@pytest.mark.parametrize("cls", FAMILIES)
def test_every_family_refuses_bad_sigma_and_margin_and_replaces_its_margin(cls):
    with pytest.raises(ValueError, match=r"^sigma must be positive, got -0.1$"):
        cls(sigma=-0.1)
    with pytest.raises(ValueError, match=r"^margin gamma must be in \(0, 1.5\], got 2.0$"):
        cls(margin=2.0)
    model = cls()
    tighter = model.with_margin(0.5)
    assert type(tighter) is cls and tighter.margin == 0.5 and model.margin == 1.0 and tighter.sigma == model.sigma


def test_a_model_without_a_margin_field_says_so():
    @dataclass(frozen=True)
    class NoMargin(TaskModelBase):
        name = "toy"

    with pytest.raises(NotImplementedError, match="the toy model has no execution margin"):
        NoMargin().with_margin(0.5)
