"""Contact constraints of one (sub)step as rows of a velocity solver (COURSE.md 5).

Each contact point has three rows: the normal n and two tangents t1, t2.
Body velocities are 6-vectors V = (v, ω) (world frame); a row's relative
velocity is J_A·V_A + J_B·V_B with

    J_A = −(d, r_A × d),   J_B = (d, r_B × d)

for its direction d, i.e. d·(v̄_B − v̄_A) with the contact-point velocities
v̄ = v + ω × r of the course. An impulse λ along the rows changes the
velocities by M⁻¹Jᵀλ, M⁻¹ = diag(1/m, I_w⁻¹), I_w⁻¹ = R diag(I⁻¹) Rᵀ: the
course's `v± = v∓ ± j n / m`, `ω± = ω∓ ± I⁻¹ (r × j n)`. The 3×3 block
W = J_A M_A⁻¹ J_Aᵀ + J_B M_B⁻¹ J_Bᵀ couples the rows; its normal entry is
the course's denominator `1/m_A + 1/m_B + [(I_A⁻¹(r_A×n))×r_A + (I_B⁻¹(r_B×n))×r_B]·n`.
Static and sleeping bodies have M⁻¹ = 0 (infinite mass, COURSE.md 5).
"""
from dataclasses import dataclass

import numpy as np

from .. import quaternion as qt
from . import friction, restitution

try:        # the C entry point of np.einsum, without the Python dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:     # pragma: no cover - other numpy layouts
    _einsum = np.einsum

_TINY = 1e-30


@dataclass
class ContactRows:
    a: np.ndarray          # (k,) body indices, normal from a towards b
    b: np.ndarray
    key: np.ndarray        # (k,) Manifold feature key
    point: np.ndarray      # (k, 3) m
    normal: np.ndarray     # (k, 3)
    tangent: np.ndarray    # (k, 2, 3) t1, t2
    depth: np.ndarray      # (k,) m, at the detected pose (> 0 overlapping)
    ab: np.ndarray         # (k, 2) the two bodies, to gather (V_a, V_b) as one 12-vector
    J: np.ndarray          # (k, 3, 12) rows n, t1, t2: (J_A | J_B)
    M: np.ndarray          # (k, 3, 12) (M_A⁻¹ J_Aᵀ | M_B⁻¹ J_Bᵀ) as rows: Δ(V_a, V_b) per unit impulse
    mass_n: np.ndarray     # (k,) 1 / W_nn, the normal's effective mass, kg
    w_tn: np.ndarray       # (k, 2) W_tn: tangential velocity change per unit normal impulse
    wtt: np.ndarray        # (k, 2, 2) the tangent block W_tt
    wtt_inv: np.ndarray    # (k, 2, 2) its inverse
    Js: np.ndarray         # (k, 3, 12) rows scaled for the solver: (m_n J_n, W_tt⁻¹ J_t)
    mass_bias: np.ndarray  # (k,) m_n · bias
    g_tn: np.ndarray       # (k, 2) W_tt⁻¹ W_tn
    mu_s: np.ndarray       # (k,)
    mu_k: np.ndarray
    mu: np.ndarray         # (k,) the one in use this substep (friction.coefficient_in_use)
    sliding: np.ndarray    # (k,) bool: held by kinetic friction this substep
    e: np.ndarray          # (k,) pair C_R (before the resting-contact rule)
    u0: np.ndarray         # (k, 3) row velocities before the solve (u0[:, 0] > 0 separating), m/s
    bias: np.ndarray       # (k,) least normal velocity the solve must reach, m/s
    lam: np.ndarray        # (k, 3) accumulated impulses of the rows, N·s
    bounds: np.ndarray     # batch boundaries (rows are sorted by batch)
    split: np.ndarray      # (k, 2) mass-splitting factors of the two bodies (1 without)
    summed_from: int = 0   # rows from here on share bodies within their batch (Jacobi, summed)
    flat6: np.ndarray = None   # (k, 12) flat indices of (V_a, V_b) in V.reshape(-1), made on first use
    key_sorted: bool = False   # rows are in ascending key order (no colouring reorder)

    def __len__(self):
        return len(self.a)

    @property
    def JA(self):
        return self.J[:, :, :6]

    @property
    def JB(self):
        return self.J[:, :, 6:]

    @property
    def MA(self):
        return self.M[:, :, :6]

    @property
    def MB(self):
        return self.M[:, :, 6:]


def world_inverse_inertia(quat, inv_inertia):
    """(n, 3, 3) I_w⁻¹ = R diag(I⁻¹) Rᵀ (COURSE.md 3)."""
    R = qt.to_matrix(quat)
    return (R * inv_inertia[:, None, :]) @ R.transpose(0, 2, 1)


def body_velocities(state):
    """(n, 6) stacked (v, ω)."""
    return np.concatenate([state.vel, state.omega], axis=1)


_SIDE = np.array([-1.0, 1.0])[:, None, None]   # J_A carries −d and −r_A × d, J_B +d and r_B × d
_COFACTOR = np.array([[1.0, -1.0], [-1.0, 1.0]])   # the signs of a 2×2 inverse


def _rows_first(a):
    """(r, c, k) computed with the contacts on the last axis → (k, r, c) C-ordered."""
    return np.ascontiguousarray(a.transpose(2, 0, 1))


class RowCache:
    """What build() computes from the contact set alone, kept for the next substep.

    From one substep to the next a resting scene has the same contacts (the
    same keys, hence the same body pairs), the same awake set (World replaces
    its inverse-mass arrays when that changes) and often the same normals
    (spheres on a plane): the body pairs' gathers, friction coefficients,
    flat indices and, with unchanged normals, the tangent frame are then
    those of the last substep. Reused arrays are never written to."""

    def __init__(self):
        self.key = None
        self.masses = None      # (inv_mass, inv_inertia) arrays of the World the gathers came from
        self.normal = None
        self.ones = None

    def pairs_match(self, key, masses):
        return (self.key is not None and self.masses is not None
                and self.masses[0] is masses[0] and self.masses[1] is masses[1]
                and (self.key is key or (self.key.shape == key.shape
                                         and bool((self.key == key).all()))))


def build(model, m, pos, inv_mass, inv_inertia_w, iso_inv, V, h, params, split=None, rewound=None,
          cache=None, masses=None):
    """Rows for manifold `m` (already in batch order) at positions `pos`.

    inv_mass (n,): the solver's inverse masses (zero for static and sleeping
    bodies); inverse inertia either `inv_inertia_w` (n, 3, 3) world tensors or,
    when that is None (every body isotropic), `iso_inv` (n,) scalars. `split`
    (k, 2) multiplies each row's two inverse masses in the effective masses
    only (Jacobi mass splitting). The normal row's target `bias` keeps the pair
    from overlapping at the end of the step (speculative contact, see
    collision/__init__).

    J and M are built with the contacts on the last axis (arrays (…, k)):
    every operation then runs over long contiguous rows, where numpy is fast,
    instead of over many short ones of 3 or 12 numbers; they are handed to
    the solver contact-major, (k, 3, 12)."""
    a, b, n = m.a, m.b, m.normal
    k = len(a)
    hit = cache is not None and masses is not None and cache.pairs_match(m.key, masses)
    if hit:
        ab, ima, iia, mu_s, mu_k, e_static = (cache.ab, cache.ima, cache.iia, cache.mu_s,
                                              cache.mu_k, cache.e_static)
        flat6, flat6T = cache.flat6, cache.flat6T
    else:
        ab = np.empty((k, 2), np.int64)
        ab[:, 0] = a
        ab[:, 1] = b
        flat6 = flat6T = None
        if cache is not None and masses is not None:
            flat6 = (ab[:, :, None] * 6 + np.arange(6)).reshape(k, 12)   # solver.flat_index(ab, 6)
            flat6T = np.ascontiguousarray(flat6.T)
        ima = inv_mass[ab].T[None, :, None]
        iia = iso_inv[ab].T[None, :, None] if inv_inertia_w is None else None
        mu_s, mu_k = friction.coefficients(model, a, b)
        e_static = None
    if cache is not None and cache.normal is not None and hit and same_array(cache.normal, n):
        DT, tangent = cache.DT, cache.tangent
    else:
        DT = friction.tangent_frame_last(n)                    # (3 rows, 3, k)
        tangent = _rows_first(DT[1:])                          # (k, 2, 3) t1, t2
    # lever arms, signed by side: −r_A, +r_B (2, 3, k)
    r = np.empty((2, 3, k))
    np.multiply((m.point[:, None, :] - pos.take(ab, axis=0)).transpose(1, 2, 0), _SIDE, out=r)
    # J as (row, body, linear | angular, xyz, k): (side d, r_side × d)
    JT = np.empty((3, 2, 2, 3, k))
    np.multiply(DT[:, None], _SIDE, out=JT[:, :, 0])
    rx, ry, rz = r[None, :, 0], r[None, :, 1], r[None, :, 2]        # (1, 2, k)
    dx, dy, dz = DT[:, None, 0], DT[:, None, 1], DT[:, None, 2]     # (3, 1, k)
    ang = JT[:, :, 1]
    np.subtract(ry * dz, rz * dy, out=ang[:, :, 0])
    np.subtract(rz * dx, rx * dz, out=ang[:, :, 1])
    np.subtract(rx * dy, ry * dx, out=ang[:, :, 2])
    # M = M⁻¹ Jᵀ as rows: inverse masses scale the linear columns; the angular
    # ones take I_w⁻¹, a scalar for isotropic bodies, a 3×3 product otherwise
    MT = np.empty_like(JT)
    np.multiply(JT[:, :, 0], ima, out=MT[:, :, 0])
    if inv_inertia_w is None:
        np.multiply(ang, iia, out=MT[:, :, 1])
        if flat6T is not None:
            VT = V.reshape(-1).take(flat6T)          # (12, k) (V_a, V_b) by column
        else:
            VT = np.ascontiguousarray(V[ab].reshape(k, 12).T)
        k_a, k_b, mass_n, w_tn, wtt, wtt_inv, Js, g_tn, u0 = _terms_last(JT, MT, VT, split)
        J = _rows_first(JT.reshape(3, 12, k))
        M = _rows_first(MT.reshape(3, 12, k))
    else:
        J = _rows_first(JT.reshape(3, 12, k))
        M = _rows_first(MT.reshape(3, 12, k))     # angular columns written next
        M[:, :, 3:6] = J[:, :, 3:6] @ inv_inertia_w[a]     # I_w⁻¹ is symmetric
        M[:, :, 9:12] = J[:, :, 9:12] @ inv_inertia_w[b]
        k_a, k_b, mass_n, w_tn, wtt, wtt_inv, Js, g_tn, u0 = _terms(J, M, V[ab].reshape(k, 12), split)
    if e_static is not None:
        e = e_static
    else:
        e = restitution.pair_restitution(model, a, b, k_a, k_b, params.restitution_combine)
    if cache is not None and masses is not None:
        if not hit:
            cache.key, cache.masses = m.key, masses
            cache.ab, cache.ima, cache.iia, cache.mu_s, cache.mu_k = ab, ima, iia, mu_s, mu_k
            # every a static or asleep (zero inverse mass and inertia): e depends on b only
            cache.e_static = None
            if not ima[:, 0].any() and (iia is None or not iia[:, 0].any()) and inv_inertia_w is None:
                cache.e_static = e
            cache.flat6, cache.flat6T = flat6, flat6T
        cache.normal, cache.DT, cache.tangent = n, DT, tangent
    # Separation at the start of the step, linearised: the detected (end) pose
    # came from moving with u0, so s0 = s_end − h u0_n. A body moved back to its
    # time of impact already sits at the start of its remaining motion.
    sep_end = -m.depth
    s0 = sep_end - h * u0[:, 0]
    if rewound is not None:
        rw = rewound[a] | rewound[b]
        s0 = np.where(rw, sep_end, s0)
    # vn ≥ −s0/h: approach no faster than closes the gap in this step;
    # already overlapping (s0 < 0): just stop approaching, the overlap is
    # removed by the position pass, never by adding velocity.
    bias = -np.maximum(s0, 0.0) / h
    return ContactRows(a=a, b=b, key=m.key, point=m.point, normal=n, tangent=tangent,
                       depth=m.depth, ab=ab, J=J, M=M, mass_n=mass_n, w_tn=w_tn,
                       wtt=wtt, wtt_inv=wtt_inv, Js=Js, mass_bias=mass_n * bias,
                       g_tn=g_tn, mu_s=mu_s, mu_k=mu_k, mu=mu_k, sliding=np.ones(k, bool), e=e,
                       u0=u0, bias=bias, lam=np.zeros((k, 3)), bounds=np.array([0, k]),
                       split=_ones_split(k, cache) if split is None else split, summed_from=k,
                       flat6=flat6)


def _ones_split(k, cache):
    """(k, 2) ones (no mass splitting); read only, so kept while the count holds."""
    if cache is None:
        return np.ones((k, 2))
    if cache.ones is None or len(cache.ones) != k:
        cache.ones = np.ones((k, 2))
    return cache.ones


def same_array(x, y):
    return x.shape == y.shape and bool((x == y).all())



def _terms(J, M, VAB, split):
    """The solver's terms from contact-major J, M (k, 3, 12), with the sums in
    the same order as always: a resting stack of boxes is chaotic enough that a
    different rounding of W shows up in where its boxes end up.

    W = J M⁻¹ Jᵀ (with the split inverse masses); k_a, k_b: each body's part of
    the normal's inverse effective mass (the course's denominator is their
    sum), which also weight the two restitutions."""
    k = len(J)
    k_a = _einsum("ki,ki->k", J[:, 0, :6], M[:, 0, :6])
    k_b = _einsum("ki,ki->k", J[:, 0, 6:], M[:, 0, 6:])
    if split is not None:
        Ms = M.copy()
        Ms[:, :, :6] *= split[:, 0, None, None]
        Ms[:, :, 6:] *= split[:, 1, None, None]
    else:
        Ms = M
    W = np.empty((k, 3, 3))
    for c in range(3):
        W[:, :, c] = _einsum("kri,ki->kr", J, Ms[:, c, :])
    mass_n = 1.0 / np.maximum(W[:, 0, 0], _TINY)
    w_tn = W[:, 1:, 0]
    det = W[:, 1, 1] * W[:, 2, 2] - W[:, 1, 2] * W[:, 2, 1]
    inv_det = 1.0 / np.where(np.abs(det) > _TINY, det, _TINY)
    # [[W22, −W12], [−W21, W11]] / det
    wtt_inv = (W[:, 1:, 1:][:, ::-1, ::-1].transpose(0, 2, 1) * _COFACTOR) * inv_det[:, None, None]
    Js = np.empty_like(J)
    np.multiply(J[:, 0, :], mass_n[:, None], out=Js[:, 0, :])
    J1, J2 = J[:, 1, :], J[:, 2, :]
    Js[:, 1, :] = wtt_inv[:, 0, 0, None] * J1 + wtt_inv[:, 0, 1, None] * J2
    Js[:, 2, :] = wtt_inv[:, 1, 0, None] * J1 + wtt_inv[:, 1, 1, None] * J2
    g_tn = _einsum("kij,kj->ki", wtt_inv, w_tn)
    u0 = _einsum("kri,ki->kr", J, VAB)
    return k_a, k_b, mass_n, w_tn, W[:, 1:, 1:], wtt_inv, Js, g_tn, u0


def _terms_last(JT, MT, VT, split):
    """_terms for rows built with the contacts on the last axis (JT, MT
    (3, 2, 2, 3, k), VT (12, k)): every product runs over whole rows of k."""
    k = JT.shape[-1]
    Wb = _einsum("rbjk,cbjk->rcbk", JT.reshape(3, 2, 6, k), MT.reshape(3, 2, 6, k))   # (r, c, body, k)
    k_a, k_b = Wb[0, 0, 0], Wb[0, 0, 1]
    if split is None:
        W = Wb[:, :, 0] + Wb[:, :, 1]
    else:
        W = Wb[:, :, 0] * split[:, 0] + Wb[:, :, 1] * split[:, 1]
    mass_n = 1.0 / np.maximum(W[0, 0], _TINY)
    det = W[1, 1] * W[2, 2] - W[1, 2] * W[2, 1]
    inv_det = 1.0 / np.where(np.abs(det) > _TINY, det, _TINY)
    wtt_inv = W[1:, 1:][::-1, ::-1].transpose(1, 0, 2) * (_COFACTOR[:, :, None] * inv_det)
    J = JT.reshape(3, 12, k)
    JsT = np.empty((3, 12, k))
    np.multiply(J[0], mass_n, out=JsT[0])
    J1, J2 = J[1], J[2]
    JsT[1] = wtt_inv[0, 0] * J1 + wtt_inv[0, 1] * J2
    JsT[2] = wtt_inv[1, 0] * J1 + wtt_inv[1, 1] * J2
    w_tn = W[1:, 0]
    g_tn = _einsum("ijk,jk->ik", wtt_inv, w_tn)
    u0 = _einsum("rik,ik->rk", J, VT)
    return (k_a, k_b, mass_n, w_tn.T, W[1:, 1:].transpose(2, 0, 1), wtt_inv.transpose(2, 0, 1),
            _rows_first(JsT), g_tn.T, u0.T)
