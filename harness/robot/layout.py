"""Where each parameter of a serial robot sits in its parameter vector pi.

pi is the regressor's order (fmu/src/core/rigid_body.h): each link's standard
parameters in turn (m, m c, I about the frame origin), then each joint's friction
(viscous, Coulomb), then the extra joint terms of harness.robot.joint_terms, joint by
joint (each joint's terms in the order of JointTerms.kinds).  The sizes and offsets are
read from the native library, so that Python keeps no copy of the C layout.
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..native_library import load_library


@dataclass(frozen=True)
class CoreLayout:
    """The C core's layout constants (rigid_body.h)."""

    link_size: int      # RB_LINK_PARAMETERS: standard parameters of a link
    friction_size: int  # RB_JOINT_FRICTION: friction parameters of a joint
    mass: int           # RB_MASS: the mass's offset in a link's parameters
    viscous: int        # RB_VISCOUS: the viscous level's offset in a joint's friction
    coulomb: int        # RB_COULOMB: the Coulomb level's offset in a joint's friction
    first_moment: int   # RB_FIRST_MOMENT: m c's offset in a link's parameters (3 values)


@lru_cache(maxsize=1)
def core_layout() -> CoreLayout:
    """The layout constants of the native library in use."""
    dll = load_library()
    dll.rn_layout.argtypes = [ctypes.POINTER(ctypes.c_int)]
    dll.rn_layout.restype = None
    values = (ctypes.c_int * 6)()
    dll.rn_layout(values)
    return CoreLayout(*(int(value) for value in values))


@dataclass(frozen=True)
class ParameterLayout:
    """The parameter vector of a robot with `joints` joints and `terms_per_joint` extra
    joint terms each: slices and indices into it, and its split into blocks."""

    joints: int
    terms_per_joint: int = 0  # extra joint terms of each joint: len(JointTerms.kinds)

    @property
    def link_size(self) -> int:
        """Standard parameters per link."""
        return core_layout().link_size

    @property
    def friction_size(self) -> int:
        """Friction parameters per joint."""
        return core_layout().friction_size

    @property
    def link_end(self) -> int:
        """Where the links' parameters end and the friction starts."""
        return self.link_size * self.joints

    @property
    def standard_size(self) -> int:
        """The core's parameters: the links' and the friction's (where the terms start)."""
        return self.link_end + self.friction_size * self.joints

    @property
    def size(self) -> int:
        """The whole vector: the core's parameters and the extra joint terms."""
        return self.standard_size + self.terms_per_joint * self.joints

    @property
    def links(self) -> slice:
        """Every link's parameters."""
        return slice(0, self.link_end)

    @property
    def friction(self) -> slice:
        """Every joint's friction."""
        return slice(self.link_end, self.standard_size)

    @property
    def standard(self) -> slice:
        """The core's parameters (links and friction)."""
        return slice(0, self.standard_size)

    @property
    def extra(self) -> slice:
        """The extra joint terms."""
        return slice(self.standard_size, self.size)

    def link(self, i: int) -> slice:
        """Link i's standard parameters."""
        return slice(self.link_size * i, self.link_size * (i + 1))

    def mass(self, i: int) -> int:
        """The index of link i's mass."""
        return self.link_size * i + core_layout().mass

    def first_moment(self, i: int) -> slice:
        """Link i's first moment m c (3 values, in its joint frame)."""
        start = self.link_size * i + core_layout().first_moment
        return slice(start, start + 3)

    @property
    def masses(self) -> slice:
        """Every link's mass."""
        return slice(core_layout().mass, self.link_end, self.link_size)

    def viscous(self, i: int) -> int:
        """The index of joint i's viscous friction."""
        return self.link_end + self.friction_size * i + core_layout().viscous

    def coulomb(self, i: int) -> int:
        """The index of joint i's Coulomb friction."""
        return self.link_end + self.friction_size * i + core_layout().coulomb

    @property
    def viscous_levels(self) -> slice:
        """Every joint's viscous friction."""
        return slice(self.viscous(0), self.standard_size, self.friction_size)

    @property
    def coulomb_levels(self) -> slice:
        """Every joint's Coulomb friction."""
        return slice(self.coulomb(0), self.standard_size, self.friction_size)

    @property
    def coulomb_indices(self) -> np.ndarray:
        """Every joint's Coulomb friction's index, as an integer array."""
        return np.arange(self.coulomb(0), self.standard_size, self.friction_size)

    def term(self, i: int, j: int) -> int:
        """The index of joint i's extra term j (j-th of JointTerms.kinds)."""
        return self.standard_size + self.terms_per_joint * i + j

    def indices(self, part: slice) -> np.ndarray:
        """The indices of a part of the vector (one of the slices above), as an array."""
        return np.arange(self.size)[part]

    def split(self, pi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """pi (size,) as views (links (joints, link_size), friction (joints,
        friction_size), terms (joints, terms_per_joint)); ValueError if pi is not as long
        as the layout."""
        if np.shape(pi) != (self.size,):
            raise ValueError(f"{np.size(pi)} parameters, the layout has {self.size}")
        n = self.joints
        return (pi[self.links].reshape(n, self.link_size),
                pi[self.friction].reshape(n, self.friction_size),
                pi[self.extra].reshape(n, self.terms_per_joint))

    def join(self, links: np.ndarray, friction: np.ndarray,
             terms: np.ndarray | None = None) -> np.ndarray:
        """The vector pi of split's blocks (terms None: no extra terms)."""
        blocks = [np.ravel(links), np.ravel(friction)]
        if terms is not None:
            blocks.append(np.ravel(terms))
        pi = np.concatenate(blocks)
        if pi.shape != (self.size,):
            raise ValueError(f"{pi.size} parameters, the layout has {self.size}")
        return pi
