"""Configuration of the foreground models: which model and how it separates people from the floor.

Why the defaults are what they are: ``benchmarks/results/tuning_foreground.md``.
"""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import Field

from worldtrack.config import Section

#: Foreground model names (``--foreground``).
FOREGROUND_KINDS = ("grey", "colour", "mog2", "knn")
#: Difference thresholds of the static models when none is given: grey levels, and RGB distance.
#: 30 suits compressed surveillance video; clean cameras separate people better at 20.
DEFAULT_THRESHOLDS = {"grey": 25.0, "colour": 30.0}
#: The threshold the synthetic world's experiments use (noise σ ≈ 3).
SYNTHETIC_COLOUR_THRESHOLD = 20.0
#: The shadow test of a method that has none of its own (``foreground.shadow_test``).
DEFAULT_SHADOW_TEST = "colour"


class ForegroundConfig(Section):
    """How every camera's frames become foreground (one model per camera, the same for every tracker)."""

    path: ClassVar[str] = "foreground"
    kind: Literal["grey", "colour", "mog2", "knn"] = Field(
        "colour", description="grey difference (paper 000), colour difference, or OpenCV's adaptive mog2/knn")
    threshold: float | None = Field(
        None, gt=0, allow_inf_nan=False,
        description="difference threshold of grey/colour: grey levels or RGB distance (null: the method's own, 25 for the particle tracker, else 25 grey, 30 colour)")
    shadows: bool | None = Field(
        None, description="set cast shadows apart as unsure (null: on except for grey, the paper's)")
    shadow_texture_ncc: float | None = Field(
        None, ge=-1, le=1, description="with shadows: shadow-like pixels whose texture correlates with the "
                                       "background's at most this much are cloth (null: off; hurt on PETS)")
    shadow_test: Literal["colour", "evidence", "evidence-background", "evidence-sure",
                         "evidence-above-feet"] | None = Field(
        None, description="with shadows, for grey/colour: 'colour' leaves shadow-like changes unsure; "
                          "'evidence' calls them foreground where the floor's pattern is gone or they "
                          "are darker than the frame's shadows (worldtrack.foreground.evidence); "
                          "'evidence-background' also calls the ones where the floor's pattern shows "
                          "through background; 'evidence-sure' is 'evidence' deciding only on "
                          "pooled evidence beyond ±4, not ±1.5; 'evidence-above-feet' is 'evidence-sure' "
                          "calling no cloth in a silhouette's lowest tenth or below (contact shadows) "
                          "(null: the method's own, evidence for the "
                          "particle tracker, else colour)")

    def resolved_threshold(self) -> float | None:
        """The threshold in use: :attr:`threshold`, else the default of :attr:`kind` (None for mog2/knn)."""
        return self.threshold if self.threshold is not None else DEFAULT_THRESHOLDS.get(self.kind)

    def resolved_shadow_test(self) -> str:
        """The shadow test in use: :attr:`shadow_test`, else ``"colour"`` (a run's configuration fills in
        the method's own first, :func:`worldtrack.trackers.method_shadow_test`)."""
        return self.shadow_test or DEFAULT_SHADOW_TEST

    def resolved_shadows(self) -> bool:
        """Whether shadows are set apart: :attr:`shadows`, else on for every kind but grey."""
        return (self.kind != "grey") if self.shadows is None else self.shadows


__all__ = ["DEFAULT_SHADOW_TEST", "DEFAULT_THRESHOLDS", "FOREGROUND_KINDS", "ForegroundConfig", "SYNTHETIC_COLOUR_THRESHOLD"]
