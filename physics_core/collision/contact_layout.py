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

# direction d_r of row r: DIR + 3 r (n, t1, t2)
DIR = 0
# lever-arm products r × d_r of body a and of body b: ARM_A + 3 r, ARM_B + 3 r
ARM_A = 9
ARM_B = 18
# angular velocity change per unit impulse, I_w⁻¹ (r × d_r): TURN_A + 3 r, TURN_B + 3 r
TURN_A = 27
TURN_B = 36
INV_MASS_A = 45          # 1/m of the two bodies (0: static or asleep)
INV_MASS_B = 46
MASS_N = 47              # 1 / W_00, the normal's effective mass, kg
W_TT = 48                # tangent block W_tt (2×2, row-major)
W_TT_INV = 52            # its inverse
G_TN = 56                # W_tt⁻¹ W_tn (2), W_tn the tangential velocity change per unit normal impulse
MU = 58                  # friction coefficient in use this substep
MU_S = 59
MU_K = 60
E = 61                   # pair coefficient of restitution (before the resting-contact rule)
U0 = 62                  # row velocities before the solve (3), u0_n > 0 separating, m/s
BIAS = 65                # least normal velocity the solve must reach, m/s
LAM = 66                 # accumulated impulses of the three rows (3), N·s
DEPTH = 69               # penetration at the detected pose, m (> 0 overlapping)
K_A = 70                 # body a's and b's parts of W_00 (they weight restitution)
K_B = 71
NCOL = 72

# int64 columns
BODY_A = 0
BODY_B = 1
SLIDING = 2              # 1: kinetic friction this substep, 0: static
ICOL = 3
