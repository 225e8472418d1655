"""The frozen model: every scene parameter, as flat read-only numpy arrays.

Kept apart from the mutable State (MuJoCo's model/data split) so that a step
can never change what the scene declared, and reset is a copy of `initial`.
Arrays are named by quantity, one row per body in scene order.
"""
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Mapping, Optional

import numpy as np


def frozen_array(a, dtype=float) -> np.ndarray:
    out = np.array(a, dtype=dtype, copy=True)
    out.flags.writeable = False
    return out


@dataclass(frozen=True)
class GravitationParams:
    G: float = 6.673e-11            # m³ kg⁻¹ s⁻² (COURSE.md 2)
    softening: float = 1e-6         # m; Plummer length ε: F = G m m d / (|d|² + ε²)^1.5


@dataclass(frozen=True)
class DragParams:
    model: str = "quadratic"        # linear | quadratic | reynolds
    fluid_density: float = 1.204    # kg/m³, air at 20 °C (COURSE.md 2)
    viscosity: float = 1.81e-5      # Pa·s, air at 20 °C; used by reynolds mode
    b: float = 0.0                  # N·s/m, linear coefficient for bodies without their own
    reynolds_threshold: float = 1.0  # below: linear (Stokes) drag, above: quadratic


@dataclass(frozen=True)
class BuoyancyParams:
    fluid_density: float = 1000.0   # kg/m³
    surface_z: float = 0.0          # m; fluid fills z < surface_z
    linear_damping: float = 0.0     # N·s/m per fully submerged body, scaled by submerged fraction
    angular_damping: float = 0.0    # N·m·s per fully submerged body
    cells: int = 4                  # box split into cells³ parts to find volume and centre of buoyancy


@dataclass(frozen=True)
class SpringSet:
    """Hooke springs with dampers; body index -1 means the world (COURSE.md 2).

    A stiff spring makes the World take more sub-steps than the scene asks for,
    so that ω h ≤ 0.5 with ω = √(K/m_eff) (World.spring_substeps,
    effects/springs.stable_substeps)."""
    a: np.ndarray
    b: np.ndarray
    point_a: np.ndarray      # attachment in a's body frame (world frame if a == -1)
    point_b: np.ndarray
    stiffness: np.ndarray    # N/m
    rest_length: np.ndarray  # m
    damping: np.ndarray      # N·s/m, along the spring

    def __len__(self):
        return len(self.a)


@dataclass(frozen=True)
class Model:
    names: tuple
    index: Mapping[str, int]
    shape_type: np.ndarray
    radius: np.ndarray
    half_extents: np.ndarray
    plane_normal: np.ndarray
    plane_offset: np.ndarray
    mass: np.ndarray
    inv_mass: np.ndarray
    inertia: np.ndarray          # (n, 3) principal moments, body frame
    inv_inertia: np.ndarray
    is_static: np.ndarray
    volume: np.ndarray
    restitution: np.ndarray
    material: np.ndarray         # (n,) index into material_names
    material_names: tuple
    mu_static: np.ndarray        # (M, M) symmetric
    mu_kinetic: np.ndarray
    friction_fallbacks: tuple    # material pairs that used materials.FALLBACK_FRICTION
    drag_cd: np.ndarray
    drag_area: np.ndarray        # NaN: projected area of the shape along v
    drag_b: np.ndarray           # NaN: effect default (or Stokes' 3πμL in reynolds mode)
    char_length: np.ndarray
    springs: SpringSet
    gravity: Optional[np.ndarray]
    effects: Mapping[str, Any]   # declared effect name -> its params
    dt: float
    substeps: int                # as declared; the World may run more for stiff springs (World.substeps)
    integrator: str
    initial: Mapping[str, np.ndarray]
    source_text: str = ""
    source_path: Optional[str] = None
    extra: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    accuracy: Any = None         # accuracy_params.AccuracyParams for `integrator: adaptive`

    @property
    def n(self) -> int:
        return len(self.names)

    @property
    def dynamic(self) -> np.ndarray:
        return ~self.is_static
