"""Parameters of the follower (seed 001): :class:`FollowConfig`, the published preset and the ablations.

The paper gives k = 1.0 m⁻¹ (eq. 2), p = 0.25 and α_th = 0.8 (eq. 3) and the method of every step,
but no detection thresholds, histogram sizes, Kalman noises, decision threshold or update
interval. Each default below says whether it is the paper's number or ours, and why.

Presets (:meth:`FollowConfig.preset`):

* ``paper`` — the method as published: HS histogram of the white-balanced image, α = p·|W| from
  the camera's gain change, D of eq. 3, the smallest D under the threshold, the template refreshed
  every N frames when α ≥ α_th and D is small; nobody else is tracked.
* ``default`` — worldtrack's: the known gains undone before the histogram (von Kries) and the
  remaining change of the light's colour measured instead (grey world on the background), a floor
  on the position weight, a gate that grows while the target is hidden, a short-term template
  beside the long-term one, and every other person tracked so that a crossing cannot swap the
  target (one assignment of all candidates to all people).
* ablations: ``colour-only`` (D = RBhat, the paper's previous system), ``position-only`` (D = E),
  ``paper+undo`` (the paper's D on gain-corrected colour), ``paper+undo+others`` (and the others
  tracked).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

from worldtrack.errors import InputError

NORMALISATIONS = ("none", "gains", "gains+greyworld")
WEIGHTINGS = ("illumination", "colour", "position")
PRESETS = ("default", "paper", "colour-only", "position-only", "paper+undo", "paper+undo+others")


@dataclass(frozen=True)
class FollowConfig:
    """Parameters of :class:`~worldtrack.follow.tracker.FollowTracker`; lengths in metres, times in seconds.

    Plan-view detection (§2.3; no numbers in the paper — ours)
        cell : plan-view grid cell (0.05 m). smooth : Gaussian σ of the occupancy map (0.06 m).
        min_point_height, max_point_height : points between these heights count as occupancy
        (0.25–2.3 m: above the floor's noise, below a doorway). structure_height : a cell holding
        points above this (2.4 m) is a wall or a building, never a person. person_top : the
        highest point of a person (1.1–2.2 m). min_area : measured surface (m²) a candidate needs
        (0.03 m²: stereo measures 0.15–0.3 m² of a whole standing person — textureless clothing
        leaves holes — so this keeps people half hidden; noise specks measure under 0.015 m²).
        min_points : and at least this many measured points (15). max_extent : a candidate's floor extent (1.0 m).
        peak_separation : nearest two people can stand, centre to centre (0.4 m).
        person_radius : points within this of a peak belong to it (0.35 m). max_range : depth
        beyond which stereo is too noisy to use (8 m). stride : pixel step of the depth image read
        (0: about 160 columns whatever the resolution). wall_margin : points closer than this to
        a wall of the scene's walkable area are dropped (0.3 m: stereo noise at 6 m). surface_offset : the camera sees
        a person's near surface; its mean lies π/4·r ≈ 0.10 m nearer than the body axis for a
        body of radius r ≈ 0.13 m, so each candidate is pushed back by this along the view ray.
    Colour (eq. 1)
        hue_bins, sat_bins : HS histogram size (16 × 8, ours). grey_bins : extra bins by value for
        achromatic pixels (saturation below ``achromatic_sat`` or value below ``achromatic_val``),
        whose hue is noise (4; 0 = the paper's pure HS histogram). normalise : "none" (the paper),
        "gains" (undo the camera's white-balance gains: von Kries) or "gains+greyworld" (then
        balance the light's colour by the grey world of the background).
    Position (eq. 2, Kalman filter)
        k : 1.0 m⁻¹ (paper). accel_sigma : white-noise acceleration of the constant-velocity model
        (2.0 m/s², a walker turning). measurement_sigma : candidate position noise (0.08 m).
    Illumination weight and decision (eq. 3)
        weighting : "illumination" (α = p·|W|, the paper), "colour" (α ≡ 0) or "position" (α ≡ 1).
        p : 0.25 (paper). alpha_th : 0.8 (paper). wb_unit : gain steps per unit of |W| (70,
        measured: see :mod:`worldtrack.follow.dissimilarity`). alpha_floor :
        α never falls below this (0 in the paper; 0.5: colour and position weigh the same when
        the light is steady). threshold : largest D accepted (0.5, ours). gate : largest distance
        from the prediction accepted (inf in the paper; 1.0 m), growing by gate_growth m/s while
        the target is unseen, up to max_gate.
    Templates (§2.4)
        update_every : the paper's "every fixed number of frames" N (10). update_max_d : "D is
        small" (0.3). short_term_tau : time constant of the short-term template (2 s; 0 = none).
    Others
        track_others : track every candidate and assign all at once (True; False in the paper).
        others_max_coast : an unseen other is dropped after this (1.5 s). reid_rbhat : a person who
        appeared while the target was lost is taken for it when their RBhat is under this (0.3).
        reid_near, reid_speed, reid_accel : and no farther from its (constant-velocity) prediction
        than ``reid_near + min(reid_speed·unseen, reid_accel·unseen²/2)`` (0.5 m, 1.5 m/s, 3 m/s²:
        how far a walker who turns or stops gets from where it was predicted — a look-alike 0.9 m
        away 0.3 s after the target vanished is not the target). reid_any_track_after : unseen this
        long (s), the target may also be any other track whose own colour fits its templates
        (RBhat < reid_rbhat), born before the loss or far from it (:mod:`~worldtrack.follow.reid`;
        3 s, the default since s11; inf = never, before). Alone it cost 66 0.497 -> 0.189 and 74
        0.760 -> 0.593 (closed loop, within ±0.3 m): every long-loss pick was the target, found 6-8 m
        away beyond an obstacle where the PID stood held; it is a default together with the
        follower's ``map_approach`` (closed loop: held-out 80-89 0.764 -> 0.866, 53-58 0.892 -> 0.892,
        never-used 90-99 0.820 -> 0.826; open loop: synth held-out 10-19 × 300 frames recall 0.901 -> 0.924,
        precision 0.991 -> 0.991; PETS unchanged 1.000 / 1.000; s10-s11). reid_holder_margin : unseen
        longer than the coast, the target may also be a candidate another track holds now if the
        templates fit it better by more than this than the holder's own histogram does (RBhat; no
        absolute RBhat needed; inf = never, the default; opt-in since s12).
        occluders : a person nearer the camera who covers the image box where the target should
        stand may be hiding it, and is never taken for it (True; False in the paper).
        height_margin : the target's height is learnt from depth (the highest point of its candidate,
        from frames that show its head, as an upper envelope, used after 2 s of such frames; see
        :mod:`~worldtrack.follow.vetoes`); a candidate more than this taller is never taken for it,
        seen or not, and when the target is found again after being unseen, or while its identity
        is on probation, neither is one this shorter with its own head seen (0.1 m: the measured top
        of one person varies by ±0.05 m; 0 = off; the paper has none).
    Identity kept open (:mod:`~worldtrack.follow.identity`; ours, the paper has none)
        identity_margin : another track whose running RBhat against the target's templates is
        lower than the followed one's by this much takes the target's place (0.4; 0 = never; 0.2
        swapped PETS 2009 crowds in dark clothes: precision 1.000 -> 0.910).
        identity_tau : time constant of those running averages (0.5 s: five
        frames at 10 fps, more than the one or two frames a mixed silhouette spoils).
        probation : the templates do not learn for this long after the target is found again
        after 0.3 s or more unseen, or taken over from another track (2 s).
    """

    cell: float = 0.05
    smooth: float = 0.06
    min_point_height: float = 0.25
    max_point_height: float = 2.3
    structure_height: float = 2.4
    person_top: tuple = (1.1, 2.2)
    min_area: float = 0.03
    min_points: int = 15
    max_extent: float = 1.0
    peak_separation: float = 0.4
    person_radius: float = 0.35
    max_range: float = 8.0
    stride: int = 0
    wall_margin: float = 0.3
    surface_offset: float = 0.10
    hue_bins: int = 16
    sat_bins: int = 8
    grey_bins: int = 4
    achromatic_sat: int = 40
    achromatic_val: int = 40
    normalise: str = "gains+greyworld"
    k: float = 1.0
    accel_sigma: float = 2.0
    measurement_sigma: float = 0.08
    weighting: str = "illumination"
    p: float = 0.25
    alpha_th: float = 0.8
    wb_unit: float = 70.0
    alpha_floor: float = 0.5
    threshold: float = 0.5
    gate: float = 1.0
    gate_growth: float = 1.0
    max_gate: float = 3.0
    update_every: int = 10
    update_max_d: float = 0.3
    short_term_tau: float = 2.0
    track_others: bool = True
    others_max_coast: float = 1.5
    reid_rbhat: float = 0.3
    reid_speed: float = 1.5
    reid_near: float = 0.5
    reid_accel: float = 3.0
    reid_any_track_after: float = 3.0
    reid_holder_margin: float = float("inf")
    occluders: bool = True
    height_margin: float = 0.1
    identity_margin: float = 0.4
    identity_tau: float = 0.5
    probation: float = 1.0

    def __post_init__(self) -> None:
        if self.normalise not in NORMALISATIONS:
            raise InputError(f"normalise: expected one of {', '.join(NORMALISATIONS)}, got {self.normalise!r}")
        if self.weighting not in WEIGHTINGS:
            raise InputError(f"weighting: expected one of {', '.join(WEIGHTINGS)}, got {self.weighting!r}")
        positive = ("cell", "min_area", "max_extent", "peak_separation", "person_radius", "max_range", "k",
                    "accel_sigma", "measurement_sigma", "wb_unit", "threshold", "gate", "max_gate")
        for name in positive:
            if not getattr(self, name) > 0:
                raise InputError(f"{name}: expected a positive value, got {getattr(self, name)!r}")
        for name in ("alpha_th", "alpha_floor"):
            if not 0 <= getattr(self, name) <= 1:
                raise InputError(f"{name}: expected a value in [0, 1], got {getattr(self, name)!r}")
        if not self.reid_holder_margin >= 0:
            raise InputError(f"reid_holder_margin: expected RBhat ≥ 0 (inf: never), got {self.reid_holder_margin!r}")
        if not self.reid_any_track_after >= 0:
            raise InputError(f"reid_any_track_after: expected seconds ≥ 0 (inf: never), got {self.reid_any_track_after!r}")
        if self.p < 0:
            raise InputError(f"p: expected a value ≥ 0, got {self.p!r}")
        if self.hue_bins < 2 or self.sat_bins < 1 or self.grey_bins < 0:
            raise InputError("hue_bins ≥ 2, sat_bins ≥ 1, grey_bins ≥ 0 expected")
        if not self.person_top[0] < self.person_top[1]:
            raise InputError(f"person_top: expected (lowest, highest) metres, got {self.person_top!r}")
        if self.stride < 0 or self.update_every < 1:
            raise InputError("stride ≥ 0 and update_every ≥ 1 expected")

    @classmethod
    def preset(cls, name: str, **overrides) -> "FollowConfig":
        """The configuration called ``name`` (see :data:`PRESETS`), with ``overrides`` applied.

        >>> FollowConfig.preset("paper").normalise, FollowConfig.preset("default").track_others
        ('none', True)
        """
        paper = dict(normalise="none", grey_bins=0, alpha_floor=0.0, gate=1e6, max_gate=1e6, gate_growth=0.0,
                     short_term_tau=0.0, track_others=False, occluders=False,
                     identity_margin=0.0, probation=0.0, height_margin=0.0)
        undo = dict(paper, normalise="gains+greyworld")
        table = {
            "default": {},
            "paper": paper,
            "colour-only": dict(paper, weighting="colour"),
            "position-only": dict(paper, weighting="position"),
            "paper+undo": undo,
            "paper+undo+others": dict(undo, track_others=True),
        }
        if name not in table:
            raise InputError(f"preset: expected one of {', '.join(PRESETS)}, got {name!r}")
        known = {f.name for f in fields(cls)}
        bad = sorted(set(overrides) - known)
        if bad:
            raise InputError(f"follow: unknown parameter(s) {', '.join(bad)}")
        return replace(cls(), **{**table[name], **overrides})
