"""Ellipsoid analysis-by-synthesis tracking (paper 000: Kato, Nakazawa & Inokuchi, 1999)."""

from worldtrack.trackers.ellipsoid.tracker import EllipsoidConfig, EllipsoidTracker

__all__ = ["EllipsoidConfig", "EllipsoidTracker"]
