"""Starting a height over (``height.reset_sigmas``): a track handed to somebody else takes their height."""

import pytest

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.config import HeightConfig
from worldtrack.trackers.ellipsoid.height import heights_due
from worldtrack.trackers.ellipsoid.height_reset import watch_samples
from worldtrack.trackers.ellipsoid.height_views import add_samples

FIRST = [1.70, 1.71, 1.70, 1.69, 1.70, 1.72, 1.70, 1.69]          # σ floor 1.5 cm: 3σ = 4.5 cm


def _person() -> Person:
    return Person(id=1, x=0.0, y=0.0, mode="tracking", height_samples=list(FIRST), height_px=[80.0] * len(FIRST))


def _feed(p: Person, heights, config: HeightConfig) -> None:
    for h in heights:
        add_samples(p, watch_samples(p, [(h, 80.0)], config), config)


def test_three_disagreeing_measurements_in_a_row_replace_the_samples():
    p, config = _person(), HeightConfig(samples=8, reset_sigmas=3.0, reset_after=3)
    _feed(p, [1.86, 1.87], config)
    assert p.height_samples == FIRST                               # two doubts: held back
    _feed(p, [1.85], config)
    assert p.height_samples == [1.86, 1.87, 1.85] and p.height_px == [80.0] * 3 and not p.height_doubts
    _feed(p, [1.86], config)                                       # the new person, measured on
    assert p.height_samples == [1.86, 1.87, 1.85, 1.86]


def test_an_agreeing_measurement_between_doubts_and_small_differences_keep_the_height():
    p, config = _person(), HeightConfig(samples=8, reset_sigmas=3.0, reset_after=3)
    _feed(p, [1.86, 1.87, 1.71, 1.86, 1.87, 1.74, 1.66], config)   # 1.74, 1.66: within 4.5 cm
    assert p.height_samples == FIRST                               # full: agreeing ones are dropped
    assert p.height_doubts == []


def test_off_by_default_nothing_is_held_back():
    p, config = _person(), HeightConfig(samples=11)
    assert config.reset_sigmas == 0
    _feed(p, [1.86, 1.87, 1.85], config)
    assert p.height_samples == FIRST + [1.86, 1.87, 1.85]


@pytest.mark.parametrize("reset", [0.0, 3.0])
def test_measuring_goes_on_after_the_samples_are_in_only_with_the_reset(reset):
    config = HeightConfig(samples=len(FIRST), reset_sigmas=reset)
    p = _person()
    p.height_tries = 20                                            # past the first measurements' every frame
    due = [k for frame in range(10) for k in heights_due([p], config, frame)]
    assert len(due) == (2 if reset else 0)                         # one frame in five


def test_the_limit_is_reset_sigmas_times_the_spread_at_least_its_floor():
    config = HeightConfig(samples=8, reset_sigmas=3.0, reset_after=3)
    p = _person()
    _feed(p, [1.755, 1.755, 1.755], config)                        # 5.5 cm off: beyond 3 × 1.5 cm
    assert p.height_samples == [1.755] * 3
    p = _person()
    _feed(p, [1.74, 1.74, 1.74], config)                           # 4 cm off: within
    assert p.height_samples == FIRST
    wide = Person(id=2, x=0.0, y=0.0, height_samples=[1.60, 1.70, 1.80, 1.65, 1.75], height_px=[80.0] * 5)
    _feed(wide, [1.84, 1.84, 1.84], HeightConfig(samples=5, reset_sigmas=3.0, reset_after=3))
    assert wide.height_samples[:5] == [1.60, 1.70, 1.80, 1.65, 1.75]   # MAD 5 cm: 14 cm is within 3σ


def test_doubts_that_scatter_do_not_start_the_height_over():
    config = HeightConfig(samples=8, reset_sigmas=3.0, reset_after=3)
    p = _person()
    _feed(p, [1.83, 1.90, 1.78], config)                           # all off, but 12 cm apart: no one person
    assert p.height_samples == FIRST
    _feed(p, [1.79, 1.80], config)                                 # now three alike (1.78-1.80)
    assert p.height_samples == [1.78, 1.79, 1.80]
