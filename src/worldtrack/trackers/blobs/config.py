"""Configuration of the blobs baseline: what a practitioner would pick, by step.

The history behind each default is in ``benchmarks/results/tuning_blobs.md``.
"""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import Field, model_validator

from worldtrack.config import Section


class BlobForeground(Section):
    """Step 1–2: MOG2 foreground and morphology (the model the tracker builds for each camera)."""

    path: ClassVar[str] = "blobs.foreground"
    mog2_history: int = Field(500, ge=1, description="frames of MOG2 history (OpenCV's default)")
    mog2_var_threshold: float = Field(16.0, gt=0, allow_inf_nan=False,
                                      description="squared Mahalanobis distance for a pixel to match the "
                                                  "background model (OpenCV's default)")
    detect_shadows: bool = Field(True, description="MOG2 shadow detection; shadow pixels count as background")
    learning_rate: float | None = Field(None, description="MOG2 rate per frame; -1 OpenCV's automatic, null "
                                                          "1/mog2_history (what the automatic rate settles at)")
    open_px: int = Field(2, ge=0, description="radius of the opening that removes speckle, px (0: none)")
    close_px: int = Field(5, ge=0, description="radius of the closing after it (holes, legs joined), px")

    @model_validator(mode="after")
    def _rate(self) -> "BlobForeground":
        r = self.learning_rate
        if r is not None and not (r == -1 or 0 <= r <= 1):
            raise ValueError(f"learning_rate: expected -1 (automatic) or a rate in [0, 1], got {r!r}")
        return self


class BlobDetection(Section):
    """Step 3–4: blobs → foot points on the floor, fused over the cameras."""

    path: ClassVar[str] = "blobs.detection"
    foot_point: Literal["bottom", "box"] = Field("bottom", description="the mean column of the blob's lowest "
                                                                       "rows, or the centre of its box")
    foot_band: float = Field(0.05, ge=0, le=1, description="share of the blob's height that counts as its bottom")
    min_area_px: int = Field(150, ge=1, description="blobs smaller than this are noise, px")
    min_area_fraction: float = Field(0.25, ge=0, lt=10, description="blobs smaller than this share of a standing "
                                                                    "person's image area at their foot are dropped")
    merge_distance_m: float = Field(0.5, gt=0, allow_inf_nan=False,
                                    description="points of different cameras closer than this are one person, m")


class BlobFilter(Section):
    """Step 5: Stone Soup's constant-velocity Kalman filter and nearest-neighbour assignment."""

    path: ClassVar[str] = "blobs.filter"
    process_noise: float = Field(0.5, gt=0, allow_inf_nan=False,
                                 description="spectral density q of the white-noise acceleration, m²/s³")
    measurement_noise_m: float = Field(0.1, gt=0, allow_inf_nan=False,
                                       description="1-σ error of a foot point on each floor axis, m")
    initial_speed_sigma: float = Field(1.5, gt=0, allow_inf_nan=False,
                                       description="1-σ of a new track's velocity on each axis, m/s")
    gate: float = Field(3.0, gt=0, allow_inf_nan=False,
                        description="Mahalanobis distance (not squared) beyond which a detection cannot update "
                                    "a track")


class BlobLifecycle(Section):
    """When tracks start and end."""

    path: ClassVar[str] = "blobs.lifecycle"
    init_min_points: int = Field(3, ge=1, description="detections a tentative track needs to be confirmed")
    init_delete_after_s: float = Field(0.5, gt=0, allow_inf_nan=False,
                                       description="a tentative track without a detection this long is dropped, s")
    delete_after_s: float = Field(1.0, gt=0, allow_inf_nan=False,
                                  description="a confirmed track without a detection this long ends, s")
    report_coasting: bool = Field(True, description="also report confirmed tracks not updated in this frame "
                                                    "(predicted, flagged coasting)")


class BlobConfig(Section):
    """The blobs baseline (MOG2 blobs + Stone Soup), by step."""

    path: ClassVar[str] = "blobs"
    #: The foreground threshold a run of this method gets when none is given (None: the kind's default;
    #: it detects with its own MOG2).
    foreground_threshold: ClassVar[float | None] = None
    foreground: BlobForeground = Field(BlobForeground(), description="MOG2 foreground and morphology")
    detection: BlobDetection = Field(BlobDetection(), description="blobs to floor points")
    filter: BlobFilter = Field(BlobFilter(), description="Kalman filter and assignment")
    lifecycle: BlobLifecycle = Field(BlobLifecycle(), description="track start and end")


__all__ = ["BlobConfig", "BlobDetection", "BlobFilter", "BlobForeground", "BlobLifecycle"]
