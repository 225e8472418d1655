"""The embedded Runge–Kutta pairs of `integrator: adaptive` as Butcher tableaux.

Each pair advances with the higher-order weights b (local extrapolation) and
estimates the local error of the lower-order solution by h Σ e_j k_j with
e = b − b̂. Both pairs are FSAL ("first same as last"): their last stage is
the new state itself, so an accepted step's last slope is the next step's
first and a step costs s − 1 force evaluations.

- Dormand–Prince 5(4) (Dormand & Prince 1980; Hairer, Nørsett & Wanner,
  Solving ODEs I, table II.5.2): 7 stages, 6 evaluations a step.
- Bogacki–Shampine 3(2) (Bogacki & Shampine 1989; MATLAB's ode23): 4 stages,
  3 evaluations a step; cheaper per step, for loose tolerances.

`error_exponent` is 1 / (q + 1), q the order of the error estimate's lower
member: the step-size controller (adaptive.py) scales h by err^(−exponent).
"""
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Tableau:
    name: str
    A: np.ndarray          # (s, s) stage coefficients, strictly lower triangular
    b: np.ndarray          # (s,) weights of the propagated (higher-order) solution
    e: np.ndarray          # (s,) b − b̂: weights of the local error estimate
    order: int             # of the propagated solution
    error_exponent: float  # 1 / (lower order + 1)
    pi_beta: float         # β of the PI step-size controller (adaptive.py)

    @property
    def stages(self) -> int:
        return len(self.b)


def _tableau(name, rows, b, b_hat, order, lower, beta):
    s = len(b)
    A = np.zeros((s, s))
    for i, row in enumerate(rows, start=1):
        A[i, :len(row)] = row
    b, b_hat = np.array(b, dtype=float), np.array(b_hat, dtype=float)
    return Tableau(name, A, b, b - b_hat, order, 1.0 / (lower + 1), beta)


DORMAND_PRINCE = _tableau(
    "dormand_prince",
    [[1 / 5],
     [3 / 40, 9 / 40],
     [44 / 45, -56 / 15, 32 / 9],
     [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
     [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
     [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]],
    b=[35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0],
    b_hat=[5179 / 57600, 0.0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40],
    order=5, lower=4, beta=0.04)

BOGACKI_SHAMPINE = _tableau(
    "bogacki_shampine",
    [[1 / 2],
     [0.0, 3 / 4],
     [2 / 9, 1 / 3, 4 / 9]],
    b=[2 / 9, 1 / 3, 4 / 9, 0.0],
    b_hat=[7 / 24, 1 / 4, 1 / 3, 1 / 8],
    order=3, lower=2, beta=0.08)

METHODS = {t.name: t for t in (DORMAND_PRINCE, BOGACKI_SHAMPINE)}
