"""Finding a lost target again among the people seen now (worldtrack, beyond seed 001).

The decision of one frame gives the target the candidate that fits it; once the target has been
unseen for a while, nobody may fit, and somebody new — or somebody tracked as one of the others —
must be recognised as it. Who qualifies (:func:`reidentify`):

* candidates nobody owns, and those of tracks born after the target's last sighting where it could
  have got to (``maybe_target``): somebody seen at the same time as the target is somebody else;
* after a long loss (``reid_any_track_after`` seconds unseen), also any other track whose own colour
  — the average of its silhouettes, not one frame's — fits the target's templates
  (RBhat < ``reid_rbhat``). A target that came back far from where it was predicted (it turned
  round, or walked out of view and in again elsewhere) is first tracked as a stranger, and the
  first rule never hands it back, even while it walks past in full view. After that long the
  prediction says little, and a track carrying the target's colours is the best evidence left;
* opt-in (``reid_holder_margin`` finite, off by default): a candidate another track holds now, when
  the target's templates fit it clearly better than that track's own colour does (its RBhat against
  the templates, plus the margin, under its RBhat against the holder's own histogram). A track that
  took over the target's candidate from somebody else (a swap as they passed) carries the other
  person's colours, and its own candidate stops fitting them; such a candidate needs no absolute
  RBhat (the target's own, under other light, is often over ``reid_rbhat``);
* never one who may be hiding the target or is of another height (``hiding``), nor a piece of
  somebody another track holds now (:mod:`~worldtrack.follow.vetoes`), nor anybody farther from the
  target's prediction than a walker could have gone (:func:`within_reach`).

They must look like it (RBhat < ``reid_rbhat``) or, while it coasts (unseen up to ``coast_s``), score
like it (D < ``threshold``; later, with E discounted, that would take anybody near whose RBhat is
under 1). The smallest D wins, E counting only the distance beyond half of what a walker could have
strayed from the prediction while unseen.

>>> import numpy as np
>>> from worldtrack.follow.config import FollowConfig
>>> within_reach(np.array([[0.4, 0.0], [3.0, 0.0]]), np.zeros(2), 0.0, FollowConfig()).tolist()
[True, False]
"""

from __future__ import annotations

import numpy as np

from worldtrack.follow.colour import bhattacharyya
from worldtrack.follow.config import FollowConfig
from worldtrack.follow.dissimilarity import dissimilarity
from worldtrack.follow.observation import Observation
from worldtrack.follow.others import Others
from worldtrack.follow.templates import Templates
from worldtrack.follow.vetoes import pieces_of_others


def within_reach(xy: np.ndarray, predicted: np.ndarray, unseen: float, cfg: FollowConfig) -> np.ndarray:
    """(N,) bool: positions ``xy`` (N, 2) m no farther from the lost target's constant-velocity
    prediction ``predicted`` (2,) m than ``reid_near + min(reid_speed·unseen, reid_accel·unseen²/2)``
    after ``unseen`` seconds."""
    reach = cfg.reid_near + min(cfg.reid_speed * unseen, cfg.reid_accel * unseen ** 2 / 2)
    return np.hypot(*(np.asarray(xy, float).reshape(-1, 2) - predicted).T) <= reach


def long_lost_tracks(others: Others, templates: Templates, unseen: float, cfg: FollowConfig) -> np.ndarray:
    """(K',) ids of the other tracks that may be the target after ``unseen`` seconds without it: none
    before ``reid_any_track_after``, then every track whose own histogram fits the templates
    (RBhat < ``reid_rbhat``)."""
    if unseen < cfg.reid_any_track_after or len(others) == 0:
        return np.zeros(0, dtype=np.int64)
    return others.ids[templates.rbhat(others.hist) < cfg.reid_rbhat]


def held_by_another_clearly(hists: np.ndarray, owner: np.ndarray, others: Others, templates: Templates,
                            margin: float) -> np.ndarray:
    """(N,) bool: candidates (histograms (N, B)) held by another track (``owner`` (N,) ≥ 2) that fit
    the target's templates better, by more than ``margin``, than the holder's own histogram:
    ``RBhat(templates) + margin < RBhat(holder)``. None when ``margin`` is inf."""
    out = np.zeros(len(owner), dtype=bool)
    held = np.flatnonzero(np.isin(owner, others.ids))
    if not np.isfinite(margin) or len(held) == 0:
        return out
    rows = np.searchsorted(others.ids, owner[held])
    rb_holder = np.diagonal(bhattacharyya(hists[held], others.hist[rows]))     # ids are kept sorted
    out[held] = templates.rbhat(hists[held]) + margin < rb_holder
    return out


def reidentify(obs: Observation, owner: np.ndarray, hiding: np.ndarray, t: float, *, others: Others,
               templates: Templates, predicted: np.ndarray, last_seen: float, alpha: float, coast_s: float,
               cfg: FollowConfig) -> int:
    """Re-identify the lost target (see the module docstring).

    Parameters
    ----------
    obs : the frame's observation (N candidates); owner : (N,) int — who holds each candidate
        (0 nobody, ≥ 2 another track); changed in place: the pick becomes 1
    hiding : (N,) bool — may hide the target, or of another height: never the target
    t : s, now; others, templates : the other tracks and the target's templates
    predicted : (2,) m, the target's prediction; last_seen : s; alpha : this frame's α (eq. 3)
    coast_s : s, how long the prediction alone is trusted

    Returns
    -------
    int — the candidate taken for the target (a track that held it ends), or −1.
    """
    unseen = t - last_seen
    young_ids = others.ids[(others.born > last_seen) & others.maybe_target]
    may_be = np.concatenate([young_ids, long_lost_tracks(others, templates, unseen, cfg)])
    clearly = held_by_another_clearly(obs.hists, owner, others, templates, cfg.reid_holder_margin)
    clearly &= unseen > coast_s
    eligible = ((owner == 0) | np.isin(owner, may_be) | clearly) & ~hiding
    eligible &= ~pieces_of_others(obs.candidates.xy, (owner > 1) & ~np.isin(owner, may_be) & ~clearly)
    eligible = np.flatnonzero(eligible)
    if len(eligible) == 0:
        return -1
    c = obs.candidates
    rb = templates.rbhat(obs.hists[eligible])
    dist = np.hypot(*(c.xy[eligible] - predicted).T)
    e = cfg.k * np.maximum(0.0, dist - 0.5 * cfg.reid_speed * unseen)
    d = dissimilarity(rb, e, alpha, cfg.alpha_th)
    # Position speaks while the prediction is trusted (coasting: a change of light may have changed
    # every colour meanwhile); after that, with E discounted, colour must agree.
    looks = (rb < cfg.reid_rbhat) | ((d < cfg.threshold) & (unseen <= coast_s)) | clearly[eligible]
    ok = looks & within_reach(c.xy[eligible], predicted, unseen, cfg)
    if not ok.any():
        return -1
    pick = int(eligible[np.flatnonzero(ok)[np.argmin(d[ok])]])
    if owner[pick] > 1:
        others.remove(others.ids != owner[pick])
    owner[pick] = 1
    return pick
