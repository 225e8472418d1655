"""Graph colouring of contacts into batches that share no dynamic body.

Gauss–Seidel over contacts is sequential; within one colour no two contacts
touch the same moving body, so a whole colour is one vectorised update and
the sweep stays Gauss–Seidel between colours (Box2D v3's constraint graph
colouring). Static and sleeping bodies never conflict: their velocity is
not written.

The colouring is first-fit and speculative (Gebremedhin–Manne): every
uncoloured contact proposes the lowest colour free at both its bodies; of
the proposals that clash on a body, the lowest contact index keeps its
colour and the others try again next round. The lowest uncoloured index
always wins, so it terminates; the result depends only on the input order,
so it is deterministic. Colours are bits of a uint64 per body; contacts of a
body with more than 64 contacts go to a second tier of 64 colours, and so on.

From one substep to the next most contacts persist: they keep last
substep's colour (where it still clashes with nothing) and only the new
ones are coloured, first-fit around them.
"""
import numpy as np

WORD = 64


def color_contacts(u: np.ndarray, w: np.ndarray, n_bodies: int, prior=None) -> np.ndarray:
    """Colour (k,) int64 for contacts between bodies u and w (-1: no conflict).
    `prior` (k,): a colour to keep per contact where it still fits (-1: none)."""
    k = len(u)
    colour = np.full(k, -1, dtype=np.int64)
    used = np.zeros(n_bodies + 1, dtype=np.uint64)   # last row: the "no body" sentinel, stays 0
    if prior is not None:
        _keep_prior(u, w, prior, colour, used)
    todo = np.flatnonzero(colour < 0)
    tier = 0
    best = np.full(n_bodies * WORD, k, dtype=np.int64)   # lowest claimant per (body, colour)
    while len(todo):
        if tier:
            used = np.zeros(n_bodies + 1, dtype=np.uint64)
        todo = _color_tier(u, w, todo, colour, best, used, tier * WORD)
        tier += 1
    return colour


def _keep_prior(u, w, prior, colour, used):
    """Give contacts their prior colour (first tier only) unless two of them
    would share a colour at a body; mark the colours used."""
    idx = np.flatnonzero((prior >= 0) & (prior < WORD))
    if not len(idx):
        return
    c = prior[idx]
    ends = np.concatenate([u[idx], w[idx]])
    owner = np.concatenate([idx, idx])
    cc = np.concatenate([c, c])
    real = ends >= 0
    ends, owner, cc = ends[real], owner[real], cc[real]
    key = ends * WORD + cc
    order = np.lexsort((owner, key))
    key, owner = key[order], owner[order]
    clash = np.zeros(len(prior), bool)
    clash[owner[1:][key[1:] == key[:-1]]] = True       # the later contact of a clashing pair
    ok = idx[~clash[idx]]
    colour[ok] = prior[ok]
    bit = np.left_shift(np.uint64(1), prior[ok].astype(np.uint64))
    uo, wo = u[ok], w[ok]
    np.bitwise_or.at(used, uo[uo >= 0], bit[uo >= 0])
    np.bitwise_or.at(used, wo[wo >= 0], bit[wo >= 0])


def _color_tier(u, w, todo, colour, best, used, offset):
    one = np.uint64(1)
    deferred = []
    while len(todo):
        uu, ww = u[todo], w[todo]
        free = ~(used[uu] | used[ww])
        full = free == 0
        if full.any():
            deferred.append(todo[full])
            todo, uu, ww, free = todo[~full], uu[~full], ww[~full], free[~full]
            if not len(todo):
                break
        lowest = free & (~free + one)
        c = np.log2(lowest.astype(np.float64)).astype(np.int64)   # exact for powers of two
        hu, hw = uu >= 0, ww >= 0
        gu = np.where(hu, uu * WORD + c, 0)
        gw = np.where(hw, ww * WORD + c, 0)
        np.minimum.at(best, gu[hu], todo[hu])
        np.minimum.at(best, gw[hw], todo[hw])
        win = (~hu | (best[gu] == todo)) & (~hw | (best[gw] == todo))
        best[gu[hu]] = len(colour)
        best[gw[hw]] = len(colour)
        colour[todo[win]] = c[win] + offset
        bit = lowest[win]
        wu, ww_ = uu[win], ww[win]
        np.bitwise_or.at(used, wu[wu >= 0], bit[wu >= 0])
        np.bitwise_or.at(used, ww_[ww_ >= 0], bit[ww_ >= 0])
        todo = todo[~win]
    return np.concatenate(deferred) if deferred else np.zeros(0, dtype=np.int64)


def batches(colour: np.ndarray):
    """(order, bounds): contacts sorted by colour (stable), and the start of each
    non-empty colour's slice in that order, with len(order) appended."""
    order = np.argsort(colour, kind="stable")
    _, first = np.unique(colour[order], return_index=True)
    return order, np.append(first, len(order))
