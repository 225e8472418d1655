"""Column layout of the contact rows the compiled solver works on (COURSE.md 5).

One contact is one row of a float64 array `R` (k, NCOL) and one row of an
int64 array `I` (k, ICOL): few, contiguous arrays keep a compiled call cheap
(each array argument costs about as much to pass as the work of a small
contact) and a contact's numbers together in memory.

A contact has three constraint directions d_r, r = 0 (normal n, from body a
towards body b), 1 and 2 (tangents t1, t2). Its relative velocity along d_r
is the course's d·(v̄_b − v̄_a) with contact-point velocities v̄ = v + ω × r:

    u_r = d_r·(v_b − v_a) + (r_b × d_r)·ω_b − (r_a × d_r)·ω_a

and an impulse λ along d_r changes the velocities by
    v_a −= λ d_r / m_a,  ω_a −= λ I_wa⁻¹ (r_a × d_r),
    v_b += λ d_r / m_b,  ω_b += λ I_wb⁻¹ (r_b × d_r)
(COURSE.md 5, v± = v∓ ± j n / m, ω± = ω∓ ± I⁻¹ (r × j n)). The 3×3 block
W_rc = u_r's change per unit λ_c couples the rows; W_00 is the course's
denominator 1/m_a + 1/m_b + [(I_a⁻¹(r_a×n))×r_a + (I_b⁻¹(r_b×n))×r_b]·n.
"""

# What a sweep reads of a face's point (its normal row: the columns before
# DIR + STRIDE) comes first, in 23 consecutive columns: three or four
# cache lines of the row's nine. The normal rows of the 10,000-box
# pyramid's 62,000 points then stay in the processor's last-level cache
# from sweep to sweep, where with every column in blocks of the three
# directions they were spread over seven lines of each row.
INV_MASS_A = 0           # 1/m of the two bodies (0: static or asleep)
INV_MASS_B = 1
MASS_N = 2               # 1 / W_00, the normal's effective mass, kg
BIAS = 3                 # least normal velocity the solve must reach, m/s
LAM = 4                  # accumulated impulses of the three rows (3), N·s
DEPTH = 7                # penetration at the detected pose, m (> 0 overlapping)
# direction r (0: n, 1: t1, 2: t2) from column DIR + STRIDE r: d_r, the
# lever-arm products r × d_r of body a and of body b (ARM_A, ARM_B + STRIDE
# r), and the angular velocity change per unit impulse I_w⁻¹ (r × d_r)
# (TURN_A, TURN_B + STRIDE r), three columns each
DIR = 8
ARM_A = 11
ARM_B = 14
TURN_A = 17
TURN_B = 20
STRIDE = 15
W_TT = 53                # tangent block W_tt (2×2, row-major)
W_TT_INV = 57            # its inverse
G_TN = 61                # W_tt⁻¹ W_tn (2), W_tn the tangential velocity change per unit normal impulse
MU = 63                  # friction coefficient in use this substep
MU_S = 64
MU_K = 65
E = 66                   # pair coefficient of restitution (before the resting-contact rule)
U0 = 67                  # row velocities before the solve (3), u0_n > 0 separating, m/s
K_A = 70                 # body a's and b's parts of W_00 (they weight restitution)
K_B = 71
NCOL = 72

# int64 columns
BODY_A = 0
BODY_B = 1
SLIDING = 2              # 1: kinetic friction this substep, 0: static
ICOL = 3


def direction_columns(base):
    """The nine columns of a quantity kept for each direction (DIR, ARM_A,
    ARM_B, TURN_A or TURN_B as `base`): direction 0's three, then 1's, then 2's."""
    return [base + STRIDE * r + i for r in range(3) for i in range(3)]
