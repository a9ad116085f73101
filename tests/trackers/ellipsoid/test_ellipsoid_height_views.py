"""Which height samples a person keeps (``height.prefer_large``): the last ones, or the largest views'."""

import pytest

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.config import HeightConfig
from worldtrack.trackers.ellipsoid.height import heights_due
from worldtrack.trackers.ellipsoid.height_views import add_samples


def _person(samples=(), px=()) -> Person:
    return Person(id=1, x=0.0, y=0.0, mode="tracking", height_samples=list(samples), height_px=list(px))


def test_by_default_the_last_samples_are_kept():
    p = _person([1.90, 1.88], [40.0, 41.0])
    add_samples(p, [(1.75, 90.0), (1.76, 20.0)], HeightConfig(samples=3))
    assert p.height_samples == [1.88, 1.75, 1.76] and p.height_px == [41.0, 90.0, 20.0]


def test_with_prefer_large_the_largest_views_are_kept_and_the_newest_among_equals():
    p = _person([1.90, 1.88, 1.95], [40.0, 60.0, 40.0])
    add_samples(p, [(1.75, 90.0), (1.70, 40.0)], HeightConfig(samples=3, prefer_large=True))
    # 90 and 60 px, then the newest of the three 40 px samples; the order of measurement is kept.
    assert p.height_samples == [1.88, 1.75, 1.70] and p.height_px == [60.0, 90.0, 40.0]
    add_samples(p, [(1.74, float("inf"))], HeightConfig(samples=3, prefer_large=True))   # several views
    assert p.height_samples == [1.88, 1.75, 1.74]


def test_samples_of_unknown_view_size_are_the_first_replaced():
    p = _person([1.95, 1.96])                          # e.g. measured at birth: no size recorded
    add_samples(p, [(1.74, 50.0), (1.75, 55.0)], HeightConfig(samples=2, prefer_large=True))
    assert p.height_samples == [1.74, 1.75] and p.height_px == [50.0, 55.0]


@pytest.mark.parametrize("prefer_large", [False, True])
def test_measuring_goes_on_after_the_samples_are_in_only_with_prefer_large(prefer_large):
    full = _person([1.8] * 12, [50.0] * 12)
    config = HeightConfig(samples=12, prefer_large=prefer_large)
    due = [k for frame in range(10) for k in heights_due([full], config, frame)]
    assert len(due) == (2 if prefer_large else 0)     # one frame in five
