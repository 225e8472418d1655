"""Closed-form answers the integrators are measured against.

Each function returns the exact state at time t (SI units), so the error of
a run is a plain difference with no reference simulation in between.
"""
import math

import numpy as np


def harmonic(t, omega, x0, v0):
    """Undamped oscillator x'' = -ω² x: (x, v) at t."""
    c, s = math.cos(omega * t), math.sin(omega * t)
    return x0 * c + v0 / omega * s, -x0 * omega * s + v0 * c


def damped(t, omega0, zeta, x0, v0):
    """Under-damped oscillator x'' + 2ζω₀ x' + ω₀² x = 0 (ζ < 1): (x, v) at t."""
    wd = omega0 * math.sqrt(1.0 - zeta * zeta)
    a = zeta * omega0
    A, B = x0, (v0 + a * x0) / wd
    e, c, s = math.exp(-a * t), math.cos(wd * t), math.sin(wd * t)
    x = e * (A * c + B * s)
    v = e * ((B * wd - a * A) * c - (A * wd + a * B) * s)
    return x, v


def quadratic_drag_fall(t, g, v_terminal):
    """Fall from rest with F = m g − ½ρC_dA v² (COURSE.md 2): (distance fallen, speed).

    v = v_t tanh(g t / v_t), d = (v_t² / g) ln cosh(g t / v_t)."""
    u = g * t / v_terminal
    # ln cosh u written to stay finite for large u
    log_cosh = u + math.log1p(math.exp(-2.0 * u)) - math.log(2.0)
    return v_terminal ** 2 / g * log_cosh, v_terminal * math.tanh(u)


def kepler(t, mu, a, e):
    """Relative position and velocity of a two-body orbit started at pericentre on +x,
    moving towards +y (semi-major axis a, eccentricity e < 1, μ = G (m₁ + m₂))."""
    n = math.sqrt(mu / a ** 3)
    M = math.fmod(n * t, 2.0 * math.pi)
    E = M if e < 0.8 else math.pi
    for _ in range(50):          # Newton on Kepler's equation M = E − e sin E
        dE = (E - e * math.sin(E) - M) / (1.0 - e * math.cos(E))
        E -= dE
        if abs(dE) < 1e-15:
            break
    b = a * math.sqrt(1.0 - e * e)
    r = np.array([a * (math.cos(E) - e), b * math.sin(E), 0.0])
    Edot = n / (1.0 - e * math.cos(E))
    v = np.array([-a * math.sin(E) * Edot, b * math.cos(E) * Edot, 0.0])
    return r, v


def jacobi_elliptic(u, m):
    """(sn, cn, dn)(u | m), parameter m = k², by the arithmetic–geometric mean
    (Abramowitz & Stegun 16.4)."""
    a, b, c = [1.0], [math.sqrt(1.0 - m)], [math.sqrt(m)]
    while abs(c[-1]) > 1e-16 and len(a) < 40:
        a.append(0.5 * (a[-1] + b[-1]))
        b.append(math.sqrt(a[-2] * b[-1]))
        c.append(0.5 * (a[-2] - b[-2]))
    phi = 2.0 ** (len(a) - 1) * a[-1] * u
    for i in range(len(a) - 1, 0, -1):
        prev = phi
        phi = 0.5 * (phi + math.asin(c[i] / a[i] * math.sin(phi)))
    return math.sin(phi), math.cos(phi), math.cos(phi) / math.cos(prev - phi)


def complete_elliptic_k(m):
    """K(m) = π / (2 AGM(1, √(1−m)))."""
    a, b = 1.0, math.sqrt(1.0 - m)
    while abs(a - b) > 1e-16 * a:
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


class FreeTop:
    """Torque-free asymmetric rigid body, body-frame ω(t) (Landau & Lifshitz §37).

    Principal moments I1 < I2 < I3 on the body x, y, z axes; started with
    ω = (ω1, 0, ω3), ω1, ω3 > 0, and M² > 2 E I2 (spinning about the axis of
    largest inertia, the branch where ω3 never changes sign):
    ω1 = A1 cn τ, ω2 = A2 sn τ, ω3 = A3 dn τ.
    """

    def __init__(self, inertia, omega1, omega3):
        I1, I2, I3 = inertia
        if not I1 < I2 < I3:
            raise ValueError("principal moments must satisfy I1 < I2 < I3")
        M2 = (I1 * omega1) ** 2 + (I3 * omega3) ** 2
        E2 = I1 * omega1 ** 2 + I3 * omega3 ** 2          # 2 E
        if M2 <= E2 * I2:
            raise ValueError("needs M² > 2 E I2 (rotation about the largest-inertia axis)")
        self.A1 = math.sqrt((E2 * I3 - M2) / (I1 * (I3 - I1)))
        self.A2 = math.sqrt((E2 * I3 - M2) / (I2 * (I3 - I2)))
        self.A3 = math.sqrt((M2 - E2 * I1) / (I3 * (I3 - I1)))
        self.rate = math.sqrt((I3 - I2) * (M2 - E2 * I1) / (I1 * I2 * I3))
        self.m = (I2 - I1) * (E2 * I3 - M2) / ((I3 - I2) * (M2 - E2 * I1))
        # ω repeats after τ = 4K(m)
        self.period = 4.0 * complete_elliptic_k(self.m) / self.rate

    def omega_body(self, t):
        sn, cn, dn = jacobi_elliptic(self.rate * t, self.m)
        return np.array([self.A1 * cn, self.A2 * sn, self.A3 * dn])
