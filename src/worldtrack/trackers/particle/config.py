"""Configuration of the particle tracker (seed 004): :class:`ParticleConfig` and its published preset.

The paper's text (as we have it) gives the method but none of its numbers — no particle count, σ,
dz, T, γ, α or β survives in it. Every default below therefore says whether it is the paper's
choice of *method* and which number is ours. :meth:`ParticleConfig.paper` is the method as
published (with our numbers where it states none); the default adds worldtrack's extensions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from worldtrack.errors import InputError
from worldtrack.trackers.particle.likelihood.column import column_heights
from worldtrack.trackers.particle.resample import RESAMPLERS

LIKELIHOODS = ("column", "point")
WEIGHTINGS = ("ratio", "count")
VELOCITIES = ("object", "particle", "state", "none")
BIRTHS = ("auto", "entry", "entry+lost", "anywhere", "none")
EXPLAIN = ("all", "detection", "none")
SHADOWS = ("background", "unknown", "object")
OUT_OF_VIEW = ("unknown", "background")
PIXEL_WEIGHTS = ("none", "depth", "filter", "hidden")


@dataclass(frozen=True)
class ParticleConfig:
    """Parameters of :class:`~worldtrack.trackers.particle.ParticleTracker`.

    Attributes
    ----------
    likelihood : {"column", "point"}
        The height column (eq. 11, the paper's method) or the plain point (eq. 7, its baseline).
    particles : int
        Particles per tracking filter, N (not stated; 500).
    detection_particles : int
        Particles per detection filter (not stated; 1000).
    dz : float, metres
        Column step (not stated; 0.1 m).
    max_height : float, metres
        The height limit of objects (§4.2's assumption); the column samples ``k·dz, k = 0 … T`` with
        ``T = round(max_height / dz)`` (not stated; 1.9 m → T = 19, 20 samples).
    min_height : float, metres
        A particle is *likely* when its column sees at least this much object (``π·dz ≥ min_height``)
        in every camera that sees it — the paper's "likelihood at or above a value" that α and β
        count. Lower ``min_height`` and ``max_height`` for children or bicycles (the paper's future
        work). (Not stated; 0.8 m.)
    gamma : float
        γ: background differences ``F ≤ γ`` (Euclidean RGB distance, 0–441) count as background
        (not stated; 25).
    alpha : float in (0, 1)
        A detection filter fires when the share of its likely particles exceeds α (not stated; 0.5).
    beta : float in [0, 1)
        A tracking filter ends when the share of its likely particles falls to β or below
        (not stated; 0.1).
    noise_xy, noise_z : float, m/√s
        σ of the prediction noise ``w ~ N(0, σ²·dt)``: a random walk whose spread per second does
        not depend on the frame rate (per frame at 10 frames/s: σ/√10, 0.4 → 0.126 m). The paper's
        σ is per frame and not stated; 0.4 (``noise_z`` 0.3; see the retuning under
        ``hit_rate_object``). ``noise_z`` acts only with the point likelihood: with
        the column, each particle's z is drawn afresh at resampling (below the top its column sees)
        before anything reads it, so ``noise_z`` has no effect there (its random draws are still
        taken: the results do not depend on its value).
    velocity : {"object", "state", "particle", "none"}
        The velocity in ``x_t = x_{t−1} + v·dt + w``. ``state`` (default, not in the paper): each
        particle carries its own velocity, a constant-velocity model whose velocity walks by
        ``noise_v`` — the particles that move like the object survive resampling, so evidence adds
        up along its path. ``object``: the object centre's, from its last two positions and
        smoothed.
        ``particle``: each particle's own ``(x_{t−1} − x_{t−2}) / dt`` (the paper's eq. 2 in real
        time — its position noise becomes ~1 m/s of velocity noise per frame at 10 frames/s, so it
        keeps no velocity from frame to frame). ``none``. Along the camera's line of sight one
        frame's column hardly tells depth (entry scenario: a column 0.5 m off the person along it
        scores above the true one in 16 % of frames), and with ``object`` a filter that falls
        behind a walker coming at the camera measures a smaller velocity, falls further behind and
        stalls (0.3–0.9 m behind for seconds). Entry scenario, seeds 0–5 × tracker seeds 0, 1
        (``benchmarks/particle_entry.py``), ``object`` → ``state`` with ``foot_samples=4``: mean
        error 0.128 ± 0.005 → 0.117 ± 0.002 m, box holds centre 77.8 ± 1.8 → 85.2 ± 2.1 %, MOTA
        0.727 ± 0.031 → 0.777 ± 0.004, filters started on the truth 0.295 → 0.172 m mean error;
        tracks per person 1.60 ± 0.14 → 1.78 ± 0.12; PETS 2009 S2.L1 (3 seeds) MOTA 0.777 ± 0.022
        → 0.823 ± 0.065. Alone it held a person walking behind another worse (peak error 0.47 →
        1.06 m); that drift came from the column, not the velocities (``pixel_weights="hidden"``).
        The default — ``state`` with ``foot_samples=4``, ``pixel_weights="hidden"`` and
        ``coast_hidden=0.3`` — against the former (``object``, 2, ``none``, 0), entry seeds 0–5 ×
        tracker seeds 0, 1: mean error 0.128 ± 0.005 → 0.118 ± 0.000 m, box holds centre 77.8 ±
        1.8 → 84.3 ± 0.7 %, MOTA 0.727 ± 0.031 → 0.768 ± 0.004, tracks per person 1.60 ± 0.14 →
        1.65 ± 0.02, started on the truth 0.295 → 0.208 ± 0.056 m; PETS 2009 S2.L1 (3 seeds) MOTA
        0.777 ± 0.022 → 0.801 ± 0.041. With it, a track stopping in a doorway slows down with the
        person and the exit rule may not fire (the β rule ends it once the person has gone).
    noise_v : float, m/s/√s
        With ``velocity="state"``: σ of the random walk of each particle's own velocity,
        ``v_t = v_{t−1} + a``, ``a ~ N(0, noise_v²·dt)`` (1.0).
    coast_hidden : float in [0, 1]
        With ``velocity="state"``: a tracking filter whose columns have the lowest share ``hidden``
        of their samples hidden (occluded, or out of view; the median over its particles, in the
        camera that sees most) walks its velocities by ``noise_v · max(0, 1 − hidden /
        coast_hidden)``: with little evidence the particles keep their velocities and coast instead
        of spreading (0.3; the paper has no velocity state). Behind a nearer person it trims the
        peak error (0.45 → 0.38 m, tracker seed 0); on entry, with ``pixel_weights="hidden"``,
        tracks per person 1.82 ± 0.31 → 1.65 ± 0.02, the rest unchanged — within the spread.
        0 = off.
    velocity_spread : float, m/s
        With ``velocity="state"``: σ (per floor axis) of a new tracking filter's particle velocities
        about 0 (0.7).
    velocity_smoothing : float in (0, 1]
        Weight of the newest measurement in the object velocity (1 = the last two centres only).
    max_speed : float, m/s
        Velocities are clipped to this floor speed (3 m/s).
    weighting : {"ratio", "count"}
        How a column becomes a weight. ``count`` (the paper, eqs. 8 and 11): ``g ∝ π``, the number
        of samples on ``F > γ``. ``ratio`` (default): the likelihood ratio of "an object stands here,
        up to its best top h in [min_height, max_height]" against "no object": every sample below
        h multiplies it by ``hit_rate_object / hit_rate_background`` if it hits and by
        ``(1 − hit_rate_object) / (1 − hit_rate_background)`` if it misses. A column that misses is
        then penalised rather than just not rewarded, which makes the weight sharp along the line
        of sight, where the count is nearly flat (see ``benchmarks/particle_entry.py``).
    hit_rate_object, hit_rate_background : float in (0, 1)
        Chance that a sample on an object / on the background reads ``F > γ`` (0.6, 0.05). Below
        the waist much of a body does not read as object: trousers like the floor and the feet in
        their own shadow fall in the "no evidence" shadow class or below γ. At 0.8 a column lost
        ``log(0.2 / 0.95)`` for every such sample, and the filter moved along the line of sight
        to where the lower body showed most. Retuned together with ``noise_xy`` 0.3 → 0.4,
        ``likelihood_power`` 0.25 → 0.2, ``head_samples`` 2 → 3 and ``surface_offset`` 0.1 → 0.14
        (a random search of 40 settings on entry seeds 0–5 × tracker seeds 0, 1, then checked on
        held-out seeds 6–11, ``benchmarks/particle_entry.py``). Seeds 0–5: mean error 0.118 →
        0.107 m, box holds centre 84.7 → 92.9 %, MOTA 0.805 → 0.847, tracks per person 1.63 →
        1.47. Held-out 6–11: mean error 0.111 → 0.098 m, box 87.3 → 95.0 %, MOTA 0.875 → 0.886.
        PETS 2009 S2.L1 (3 seeds): MOTA 0.801 ± 0.041 → 0.866 ± 0.032, IDF1 0.498 → 0.491. Each
        setting alone moves these figures by about the tracker seeds' spread; the 0.8 → 0.6 step
        does most.
    likelihood_power : float
        Weights ``∝ π^κ``. The paper: κ = 1. Default 0.2, which tempers the ``ratio``: the samples
        of one column are not independent (neighbours see the same body part, a walker's legs
        swing), so counting each at full weight makes the filter collapse onto one frame's best
        column and follow the gait rather than the body.
    column_radius : float, metres
        0: the paper's column, a line of points. > 0: a sample hits if its pixel or one of the two
        pixels ``f_x·radius / depth`` to its left and right hits (its neighbours this far across the
        line of sight) — a thin cylinder, so that the gap between a walker's legs does not break
        the column (0.1 m).
    foot_samples : int
        With ``ratio``: samples at ``−dz, −2·dz, …`` below the floor (the paper has none). An object
        standing on the floor leaves them on background, so each one that hits divides the ratio by
        ``hit_rate_object / hit_rate_background``: the column's floor contact (4). A column standing
        behind the person along the line of sight gains a sample on the body for every sample it
        has there. 2 → 4 with the object velocity held filters started on the truth better (entry
        seeds 0–2: 0.366 → 0.254 m) but did not move the full run; with ``velocity="state"``
        (seeds 0–2 × tracker seeds 0, 1) mean error 0.127 → 0.123 m, box 81.6 → 83.1 %, MOTA
        0.737 → 0.756, started on the truth 0.261 → 0.180 m.
    head_samples : int
        With ``ratio``: samples at ``dz, 2·dz, …`` above the column's top. Over an object's head is
        background, so each one that hits divides the ratio by ``hit_rate_object /
        hit_rate_background``. With the foot samples this is a ring round the column (seed 000's
        −1 ring in column form): a column that stands on a body farther along the line of sight
        and stops short inside it hits both, so depth comes from the head as well as the feet (3).
    pixel_weights : {"none", "depth", "filter", "hidden"}
        With ``ratio``: weight each column sample by the image length it stands for, so the ratio
        counts pixels of evidence. Samples are evenly spaced in height, not in the image:
        unweighted (``none``, the paper), a column farther along the line of sight — shorter in the
        image — packs more samples into the same pixels of a body and wins wherever the column's
        foot cannot tell it off: when the lower body is hidden behind a nearer person or below the
        image's edge. ``depth`` (``True``): a sample's image length over that of a sample 5 m from
        the camera — on the synthetic entry scenario it raised MOTA (0.45 → 0.66) but cost position
        error (0.154 → 0.184 m), and on PETS 2009 S2.L1 (people 25–35 m away, where every weight
        is ~1/6) it dropped MOTA from 0.87 to 0.70. ``filter``: over the mean sample length of the
        column at the tracking filter's predicted centre, so weights are ~1 round each object at
        any distance (detection filters unweighted) — still worse on entry (``velocity="state"``,
        ``foot_samples=4``, seeds 0–5 × 2: mean error 0.117 → 0.209 m, estimates 0.17 m towards
        the camera). ``hidden`` (default): ``filter``, only for a tracking filter whose columns
        had more than the foot samples hidden in that camera last frame (the median over its
        particles), i.e. exactly where the foot cannot tell a far column off. A person walking
        behind another (tests/trackers/test_particle.py, ``velocity="state"``, 3 tracker seeds):
        peak error 0.86–0.95 → 0.34–0.45 m; entry with the default otherwise unchanged (0.117 →
        0.120 m, box 85.2 → 83.8 %, MOTA 0.777 → 0.766, within the tracker seeds' spread).
    top_sigma : float, metres
        With ``ratio``: each particle carries the object's height ``h`` as a fourth state variable,
        and its column's top gets a Gaussian prior about it of this σ (posture, head shape, the dz
        grid). 0: no height state, the top is free in [min_height, max_height]. One camera's column
        leaves a valley of (depth, height) pairs that fit a body; a height that persists from frame
        to frame closes it where the feet do not show (clothes like the floor, a shadow) (0.05).
    top_edge, top_edge_step, top_edge_samples
        With ``ratio`` and ``top_sigma > 0``, for tracking filters (not in the paper): the column
        reads its top on the ``dz`` grid, 5–10 pixels a step at 3–6 m. ``top_edge_samples`` (2)
        samples ``top_edge_step`` (0.03 m) apart just below each particle's own height ``h`` must
        read object and as many just above it background, each adding the column's ``on`` /
        ``off`` / ``−on`` terms, the sum weighted by ``top_edge`` (1.0; 0 = off, the paper preset).
        The top edge is then read to a pixel, and with the height held from frame to frame it fixes
        depth along the line of sight where the feet, moving with the stride, do not: a walker's
        head does not swing. Entry scenario (``benchmarks/particle_entry.py``, seeds 0–11 × tracker
        seeds 0, 1), 0 → 1: mean error 0.102 → 0.091 m (along the line of sight 0.085 → 0.077), box
        holds centre 91.9 → 94.1 %, MOTA 0.898 → 0.897 (tracker seeds 2, 3: 0.094 m); seeds 0–2:
        0.115 → 0.096 m. With a scratch copy of the same terms (seeds 0–11): weight 0.5 / 2: 0.095 /
        0.095 m; steps 0.02 m × 3: 0.090, 0.03 m × 3: 0.093; for detection filters too: 0.093 m
        (their heights have not settled); ``foot_samples`` 2 or ``head_samples`` 1 change nothing.
        PETS 2009 S2.L1 (``benchmarks/real_data.py``, 3 seeds): MOTA 0.882 ± 0.017 → 0.872 ± 0.020,
        IDF1 0.497 → 0.536.
    top_edge_explain : bool
        Read the top-edge samples as the column's are — in another tracked object's box background,
        in a nearer one's no evidence — rather than the labels as they are (False). In principle the
        consistent choice, in practice worse: entry seeds 0–11 × tracker seeds 0–3 0.093 against
        0.092 m, PETS 2009 S2.L1 MOTA 0.836 ± 0.029 against 0.872 ± 0.020 (``compare_methods.py``'
        crowd-5 scene, tracker seeds 0–2: 0.42 against 0.38; its entry scene 0.74 against 0.87).
    height_spread : float, metres
        σ of new particles' heights about the scene's person height (0.1).
    noise_h : float, m/√s
        Random walk of the particles' heights (0.02).
    shadows : {"background", "unknown", "object"}
        How cast shadows read. A pixel whose background is the walkable floor, that looks like it
        darkened without a change of colour and through which the floor's texture still shows
        (:func:`~worldtrack.trackers.particle.likelihood.hit_labels`; needs a foreground model with
        a background image) is a shadow: ``background`` (default) — a shadow on the floor otherwise
        looks like a taller object standing on it and pulls the estimate towards the camera by up
        to its length; ``unknown`` — no evidence either way (a column that stands in its object's
        shadow then loses nothing, which biases the estimate towards the camera by half the shadow,
        see ``benchmarks/particle_entry.py``); ``object`` — what F > γ says (the paper). Darkened
        pixels over a floor too plain to tell cloth from shadow read no evidence in the first two
        modes; without the texture test grey trousers over a grey floor read as shadow, the lower
        legs vanished and the column lost its floor contact (entry scenario MOTA 0.45 → 0.67).
    out_of_view : {"unknown", "background"}
        How a column sample that projects outside the image (or behind the camera) reads, with
        ``ratio`` (``count`` never counts it either way). ``background`` (the paper's: the image is
        all the evidence it has) — the sample adds the miss term, as if the camera saw floor there;
        ``unknown`` (default) — no evidence, it adds nothing. A person standing with the feet below
        the image's bottom edge gets the miss term for every sample out of view under
        ``background``, which pushes the filter away from the camera (to where the whole column is
        in view) and can make the β rule end the track mid-room. Entry scenario, seeds 0–11 ×
        tracker seeds 0, 1 (``benchmarks/particle_entry.py``), background → unknown: mean error
        0.125 → 0.122 m, box holds centre 78.4 → 80.2 %, MOTA 0.780 → 0.796, tracks per person
        1.49 → 1.48; PETS 2009 S2.L1 (``benchmarks/real_data.py``, 3 seeds) MOTA 0.771 ± 0.025 →
        0.777 ± 0.022, IDF1 0.456 ± 0.040 → 0.509 ± 0.014. Gains of the size of the seed noise,
        none worse.
    common_view : float in [0, 1]
        With ``ratio``, beyond the paper: when the lower part of a tracking filter's columns is
        hidden — occluded by a nearer object or, with ``out_of_view="unknown"``, below the image's
        edge — the columns are compared on the samples they all see. Columns farther along the
        line of sight are hidden less and, shorter in the image, pack more samples into the
        visible part of the body, so they win where nothing (the feet) tells them off. Per camera,
        the samples below the ``common_view`` quantile (over the filter's particles, last frame) of
        the number of lowest samples hidden read no evidence. 0 = off (default): 0.5 halved the
        drift behind an occluder (peak 0.86 → 0.47 m) but left entry as it was (0.117 m, box
        85.4 %) and filters started on the truth worse (0.172 → 0.262 m); higher quantiles cut
        more as the cloud spreads and lose the object (1.0: peak 1.0 m).
    explain : {"all", "detection", "none"}
        Pixels inside another tracked object's image box (its column, ``width/2 + box_margin`` to
        each side) read as background — for every filter (``all``: a filter cannot take over its
        neighbour's pixels), for detection filters only (``detection``: the least that keeps the
        fresh detection filter of §3.2 from firing again on the object it has just handed over; the
        paper does not say how it avoids that), or never.
    box_margin : float, metres
        Margin of the image boxes of ``explain`` (0.05 m).
    surface_offset : float, metres
        A particle is the object's axis on the floor, but what a camera sees lowest of a standing
        person is the near side of the feet: each camera's column stands this much nearer to it than
        the particle (a body's half-depth). Without it the estimate sits ~0.1 m towards the camera
        (entry scenario, filters started on the truth: median along-sight error 0.157 → 0.101 m,
        benchmarks/particle_entry.py). 0.14 m (the paper: 0): at 0.1 m the full entry runs still
        sat 0.04 m towards the camera on average (seeds 0–5); at 0.14 m the mean along-sight error
        is 0.00 m. The bias grows with distance (−0.02 m within 3 m, −0.10 m beyond 7 m at 0.1 m):
        part of it is the shadow at the feet.
    occlusion, occlusion_margin
        With ``explain="all"``: a column sample inside the box of another object that stands more
        than ``occlusion_margin`` (0.3 m) nearer to the camera (floor distance, as seed 000 orders
        its ellipsoids) is *occluded* — no evidence — instead of background. Without it a person
        walking behind another is penalised at their true place for every sample the nearer person
        hides, and the filter is pushed off along the line of sight or ends (True).
    appearance_weight, appearance_rate
        Beyond the paper: each tracking filter learns, per camera, the colour histogram of the
        object pixels on its column in frames where its image box overlaps no other track's (a
        running average with weight ``appearance_rate``, 0.1), and a particle's log-likelihood
        loses ``appearance_weight`` (1.0) times the log-ratio of every column colour its object
        rarely shows (:mod:`~worldtrack.trackers.particle.appearance`). It keeps a filter from
        going on with another person when two cross in one camera's image: on the entry scenario
        tracks per person 2.0 → 1.73, IDF1 0.59 → 0.68, mean error 0.144 → 0.132 m. 0 = off (the
        paper preset).
    exclusion_depth : float, metres
        For detection filters a track's box also covers the object placed this much nearer and
        farther along the line of sight: one camera places an object poorly in depth, and what the
        track's box leaves of its object must not start a second track (0.5 m).
    resampling : {"systematic", "stratified"}
        Systematic (default): one uniform number places all N pointers, so each particle is copied
        ``⌊N·g⌋`` or ``⌈N·g⌉`` times — the least resampling noise of the usual schemes, O(N) and one
        ``searchsorted``. Stratified draws one number per stratum; kept for comparison. (The paper:
        "selection with replacement in proportion to the weight", i.e. multinomial.)
    births : {"auto", "entry", "entry+lost", "anywhere", "none"}
        Where detection filters scatter: the scene's entry regions, the walkable floor in view, or
        nowhere (tracks only from ``init_track``). ``auto`` (default): ``entry+lost`` if the scene has
        entry regions, else ``anywhere``. ``entry+lost`` (not in the paper, whose detection filters
        watch the entry regions only): the entry regions, and for ``lost_hold_s`` a detection
        filter over the floor within ``lost_radius`` of where a tracking filter ended by the β rule
        outside the entry regions' detection filters — its object is probably still there (e.g. a
        person near the camera with the feet below the image's edge, or out of the image for a few
        seconds), and is found again, under its old id (``lost_same_id``), when it shows. Entry
        scenario, seeds 0–5 × tracker seeds 0, 1 (``benchmarks/particle_entry.py``), entry →
        entry+lost (5 s, same id): MOTA 0.768 ± 0.004 → 0.805 ± 0.005, IDF1 0.746 → 0.762, recall
        0.875 → 0.911, tracks/person 1.65 ± 0.02 → 1.63 ± 0.05 (one track 43 → 48 %); without
        ``lost_same_id`` MOTA 0.804 but 1.77 tracks/person; with the former 2 s watch 0.769 / 1.78.
        Scenes without entry regions (PETS) are unaffected.
    lost_radius : float, metres
        Radius of the floor region (in view) that ``births="entry+lost"`` watches round a lost
        track's last position (1.0).
    lost_hold_s : float, s
        How long that region is watched, from the end of the track (5.0; 0 = no watch, as in the
        paper); a watch that starts a track ends then. The 5 s cover people who walk out of the
        image's bottom edge close to the camera and come back (entry scenario: 2–4 s unseen).
    lost_same_id : bool
        The biggest lump a lost track's watch starts takes the lost track's id (the object found
        again; not in the paper, where every detection is a new object) rather than a new one (True).
    entry_margin : float, metres
        An entry region's detection filter covers the walkable floor within this distance of its
        polygon (people become fully visible near a door, often not in it; 0 = the polygon). Every
        detection region keeps only floor where a column of ``min_height`` is in some image (1.0).
    entry_reach : float, metres
        Where an entry region is partly or wholly out of view, people come out of it into view
        across the view's edge, not in front of the door: its detection filter also covers the
        floor in view within ``entry_margin`` of the walkable floor out of view within
        ``entry_reach`` of the polygon (not in the paper, whose entry regions are in view). In the
        ``entry`` scenario the east door is out of the camera's view and people crossing from it
        show first 1–1.5 m from it. With the door's margin alone, a person walking in along the
        door's axis was found up to 5 s late, and only by the lost-track watch of someone else. Entry
        seeds 0–11 × tracker seeds 0, 1, 0 → 2 m: one track on entry (within 5 frames of fully in
        view) 88.3 → 95.0 % of people, MOTA 0.867 → 0.889, IDF1 0.838 → 0.859 (2.0; 0 = off, the
        paper preset).
    detection_reseed : float in [0, 1]
        Share of a detection filter's particles scattered afresh every frame. The rest are
        resampled and jittered, so the filter concentrates on what enters (0.2). 1 = scatter all
        afresh every frame, the literal reading of §3.2 (α must then be below an object's share of
        the region's area).
    detection_noise : float, m/√s
        σ of the jitter of detection particles (0.15).
    end_after_s : float, s
        A tracking filter ends once its share has stayed ≤ β this long (paper: at once, 0; 0.3).
    exit_lookahead_s, exit_speed, exit_hold_s
        Leaving through an exit (not in the paper): a tracking filter whose centre is in an entry
        region, moving at ≥ ``exit_speed`` (0.3 m/s), with its centre ``exit_lookahead_s`` ahead
        (0.3 s) off the walkable floor, ends at once — its object is walking off the known floor,
        and what its column reads there next is whoever stands in front of the door on the same
        line of sight. Its last image box stays explained for the detection filters for
        ``exit_hold_s`` (0.5 s), so the object still showing at the floor's edge is not detected
        again. ``exit_lookahead_s = 0`` turns this off (the paper preset: tracks end only by β).
        0.2 → 0.3 s: the particles weigh 0 off the floor, so a filter's centre stops short of the
        edge, and the closer it follows its walker the less 0.2 s ahead reaches past it (a walker
        stopping 0.15 m short of the edge at 1 m/s was then not ended). Entry seeds 0–11 × tracker
        seeds 0, 1: MOTA 0.883 → 0.898, tracks per person 1.42 → 1.35, IDF1 0.861 → 0.867.
    split, split_distance, split_dip, split_min_mass, split_frames
        Split a filter whose particles form two lumps on the floor at least ``split_distance`` apart
        (0.35 m), with a valley of at most ``split_dip`` (0.5) times the lower peak and at least
        ``split_min_mass`` (0.2) of the particles on each side, for ``split_frames`` (2)
        consecutive frames; a detection filter that fires on two lumps starts two tracks.
    merge, merge_overlap, merge_frames, merge_distance, merge_far_frames, merge_depth
        End the younger of two filters whose image boxes overlap by at least ``merge_overlap``
        (intersection over the smaller box, 0.6) in every camera that sees both, for
        ``merge_frames`` (3) consecutive frames, or ``merge_far_frames`` (6) if their centres are
        more than ``merge_distance`` (0.6 m) apart on the floor. One camera's boxes also overlap
        when two people pass one behind the other. That lasts a few frames, and a filter stuck
        at the wrong depth on its neighbour's object lasts longer. With ``merge_frames`` for
        both, a person walking in from the east door behind a standing person lost their new
        track. Entry seeds 0–11 × tracker seeds 0, 1: one track on entry 95.0 → 98.3 % of
        people, MOTA 0.889 → 0.883, IDF1 0.859 → 0.861 (``merge_distance = inf``: the former
        rule). It costs on PETS 2009 S2.L1 (3 seeds; people 25–35 m away, where one camera's depth
        is uncertain by more than 0.6 m): MOTA 0.866 ± 0.032 → 0.817 ± 0.030 with the exit change.
    merge_depth
        Beyond this floor distance from the nearest camera (10 m), ``merge_distance`` grows in
        proportion to the distance: one camera's depth error grows with it, and at 30 m duplicate
        filters of one person stand a metre apart. PETS 2009 S2.L1 (3 seeds): MOTA 0.817 ± 0.030
        → 0.882 ± 0.017, IDF1 0.497 both. The entry scenario's room is within 10 m of its camera.
    seed : int
        Seed of the tracker's random generator: same seed and input, same tracks.
    """

    likelihood: str = "column"
    particles: int = 500
    detection_particles: int = 1000
    dz: float = 0.1
    max_height: float = 1.9
    min_height: float = 0.8
    gamma: float = 25.0
    alpha: float = 0.5
    beta: float = 0.1
    noise_xy: float = 0.4
    noise_z: float = 0.3
    velocity: str = "state"
    velocity_smoothing: float = 0.5
    noise_v: float = 1.0
    velocity_spread: float = 0.7
    coast_hidden: float = 0.3
    max_speed: float = 3.0
    weighting: str = "ratio"
    hit_rate_object: float = 0.6
    hit_rate_background: float = 0.05
    likelihood_power: float = 0.2
    column_radius: float = 0.1
    foot_samples: int = 4
    head_samples: int = 3
    pixel_weights: str = "hidden"
    top_sigma: float = 0.05
    top_edge: float = 1.0
    top_edge_step: float = 0.03
    top_edge_samples: int = 2
    top_edge_explain: bool = False
    height_spread: float = 0.1
    noise_h: float = 0.02
    shadows: str = "background"
    out_of_view: str = "unknown"
    common_view: float = 0.0
    explain: str = "all"
    box_margin: float = 0.05
    surface_offset: float = 0.14
    occlusion: bool = True
    occlusion_margin: float = 0.3
    appearance_weight: float = 1.0
    appearance_rate: float = 0.1
    exclusion_depth: float = 0.5
    resampling: str = "systematic"
    births: str = "auto"
    entry_margin: float = 1.0
    entry_reach: float = 2.0
    lost_radius: float = 1.0
    lost_hold_s: float = 5.0
    lost_same_id: bool = True
    detection_reseed: float = 0.2
    detection_noise: float = 0.15
    end_after_s: float = 0.3
    exit_lookahead_s: float = 0.3
    exit_speed: float = 0.3
    exit_hold_s: float = 0.5
    split: bool = True
    split_distance: float = 0.35
    split_dip: float = 0.5
    split_min_mass: float = 0.2
    split_frames: int = 2
    merge: bool = True
    merge_overlap: float = 0.6
    merge_frames: int = 3
    merge_distance: float = 0.6
    merge_far_frames: int = 6
    merge_depth: float = 10.0
    seed: int = 0

    @classmethod
    def paper(cls, **overrides) -> "ParticleConfig":
        """The method as published: each particle's own velocity (eq. 2), weights ∝ count (eqs. 8,
        11) on the plain line column, shadows counted as object, samples out of view as
        background, no split, merge or explaining away for tracking filters, tracks end at once,
        detection filters on the entry regions only (no watch where a track was lost, nor the floor where
        a door out of view comes into view).
        Numbers it does not state stay ours."""
        base = cls(velocity="particle", weighting="count", likelihood_power=1.0, column_radius=0.0,
                   foot_samples=0, head_samples=0, pixel_weights="none", top_sigma=0.0, top_edge=0.0, shadows="object",
                   out_of_view="background", explain="detection",
                   occlusion=False, appearance_weight=0.0, surface_offset=0.0,
                   split=False, merge=False, entry_reach=0.0,
                   end_after_s=0.0, exit_lookahead_s=0.0, lost_hold_s=0.0)
        try:
            return replace(base, **overrides)
        except TypeError as e:
            raise InputError(f"particle tracker: {e}") from None

    def __post_init__(self) -> None:
        if isinstance(self.pixel_weights, bool):       # the former switch: True = weights relative to 5 m
            object.__setattr__(self, "pixel_weights", "depth" if self.pixel_weights else "none")

        def bad(name: str, expected: str) -> InputError:
            return InputError(f"particle tracker: {name}: expected {expected}, got {getattr(self, name)!r}")

        for name, options in (("likelihood", LIKELIHOODS), ("weighting", WEIGHTINGS), ("velocity", VELOCITIES),
                              ("births", BIRTHS), ("resampling", RESAMPLERS), ("explain", EXPLAIN), ("shadows", SHADOWS),
                              ("out_of_view", OUT_OF_VIEW), ("pixel_weights", PIXEL_WEIGHTS)):
            if getattr(self, name) not in options:
                raise bad(name, "one of " + ", ".join(options))
        for name in ("particles", "detection_particles", "split_frames", "merge_frames", "merge_far_frames"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise bad(name, "an integer ≥ 1")
        for name in ("foot_samples", "head_samples", "top_edge_samples"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise bad(name, "an integer ≥ 0")
        for name in ("dz", "max_height", "min_height", "max_speed", "velocity_smoothing", "split_distance", "top_edge_step"):
            if not _number(getattr(self, name)) or not getattr(self, name) > 0:
                raise bad(name, "a positive number")
        for name in ("gamma", "top_sigma", "top_edge", "height_spread", "noise_h", "noise_xy", "noise_z", "noise_v", "velocity_spread", "box_margin", "surface_offset", "occlusion_margin", "exclusion_depth", "detection_noise", "entry_margin",
                     "entry_reach", "lost_radius", "lost_hold_s", "end_after_s", "exit_lookahead_s", "exit_speed", "exit_hold_s", "likelihood_power", "column_radius", "appearance_weight"):
            if not _number(getattr(self, name)) or not getattr(self, name) >= 0:
                raise bad(name, "a number ≥ 0")
        for name, lo, hi, what in (("alpha", 0, 1, "(0, 1)"), ("hit_rate_object", 0, 1, "(0, 1)"),
                                   ("hit_rate_background", 0, 1, "(0, 1)"), ("split_dip", 0, 1, "(0, 1)"),
                                   ("split_min_mass", 0, 0.5, "(0, 0.5)")):
            if not _number(getattr(self, name)) or not lo < getattr(self, name) < hi:
                raise bad(name, f"a number in {what}")
        if not _number(self.beta) or not 0 <= self.beta < 1:
            raise bad("beta", "a share in [0, 1)")
        if not _number(self.coast_hidden) or not 0 <= self.coast_hidden <= 1:
            raise bad("coast_hidden", "a share in [0, 1]")
        if not _number(self.common_view) or not 0 <= self.common_view <= 1:
            raise bad("common_view", "a share in [0, 1]")
        if not _number(self.detection_reseed) or not 0 <= self.detection_reseed <= 1:
            raise bad("detection_reseed", "a share in [0, 1]")
        if not _number(self.appearance_rate) or not 0 < self.appearance_rate <= 1:
            raise bad("appearance_rate", "a weight in (0, 1]")
        for name, infinite in (("merge_distance", "boxes alone"), ("merge_depth", "merge_distance at every depth")):
            if not _number(getattr(self, name), allow_inf=True) or not getattr(self, name) > 0:
                raise bad(name, f"a positive number of metres (inf: {infinite})")
        if not _number(self.merge_overlap) or not 0 < self.merge_overlap <= 1:
            raise bad("merge_overlap", "a share in (0, 1]")
        if self.velocity_smoothing > 1:
            raise bad("velocity_smoothing", "a weight in (0, 1]")
        if not self.hit_rate_object > self.hit_rate_background:
            raise InputError("particle tracker: hit_rate_object must be above hit_rate_background")
        if self.min_height > self.max_height:
            raise InputError(f"particle tracker: min_height ({self.min_height} m) is above max_height "
                             f"({self.max_height} m)")
        if self.dz > self.max_height:
            raise InputError(f"particle tracker: dz ({self.dz} m) is above max_height ({self.max_height} m)")

    @property
    def heights(self) -> np.ndarray:
        """The column's sample heights ``k·dz``, k = 0 … T, metres."""
        return column_heights(self.max_height, self.dz)

    @property
    def likely_count(self) -> int:
        """Column samples on the object for a particle to be likely: ``⌈min_height / dz⌉``."""
        return max(1, int(math.ceil(self.min_height / self.dz - 1e-9)))


def _number(v: object, allow_inf: bool = False) -> bool:
    """Whether ``v`` is a real number (not a bool), finite unless ``allow_inf`` (never NaN)."""
    if not isinstance(v, (int, float, np.integer, np.floating)) or isinstance(v, bool):
        return False
    return not math.isnan(v) if allow_inf else math.isfinite(v)
