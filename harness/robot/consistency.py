"""Physically consistent link parameters from identified base parameters, and the identified URDF.

Identification determines only the base parameters beta.  Among the standard
parameters pi that reproduce them, the ones written to the URDF are found by a
nonlinear least-squares fit over a parametrization that is physically consistent
by construction (log-Cholesky): per link, the pseudo-inertia
    J = [[Sigma, h], [h^T, m]] = L L^T,  Sigma = tr(I_o)/2 * 1 - I_o,
with L lower triangular with positive (exponential) diagonal, is positive definite:
m > 0 and an inertia about the centre of mass that is positive definite and satisfies
the triangle inequalities.  Friction is kept >= 0.  The fit weighs the base
parameters by their standard errors and pulls weakly toward the URDF's values, which
picks them where the data say nothing.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.optimize
from lxml import etree

from .base_parameters import BaseParameters
from .urdf import Robot, body_inertial, check_inertia, inertia_matrix, parse_urdf

PRIOR_WEIGHT = 1e-3  # of the pull toward the URDF relative to one standard error


def pseudo_inertia(link: np.ndarray) -> np.ndarray:
    m, h, I = link[0], link[1:4], inertia_matrix(link[4:])
    J = np.empty((4, 4))
    J[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I
    J[:3, 3] = J[3, :3] = h
    J[3, 3] = m
    return J


def link_of_pseudo_inertia(J: np.ndarray) -> np.ndarray:
    S, h, m = J[:3, :3], J[:3, 3], J[3, 3]
    I = np.trace(S) * np.eye(3) - S
    return np.array([m, *h, I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]])


_LOWER = np.tril_indices(4)
_DIAGONAL = [k for k, (r, c) in enumerate(zip(*_LOWER)) if r == c]


def _log_cholesky(link: np.ndarray) -> np.ndarray:
    """The 10 log-Cholesky coordinates of a (near-)consistent link, made strictly
    consistent first (a small multiple of the identity added if needed)."""
    J = pseudo_inertia(link)
    scale = max(np.abs(J).max(), 1e-6)
    shift = max(0.0, 1e-6 * scale - np.linalg.eigvalsh(J)[0])
    L = np.linalg.cholesky(J + shift * np.eye(4))
    theta = L[_LOWER].copy()
    theta[_DIAGONAL] = np.log(theta[_DIAGONAL])
    return theta


def _link(theta: np.ndarray) -> np.ndarray:
    L = np.zeros((4, 4))
    values = theta.copy()
    values[_DIAGONAL] = np.exp(np.clip(values[_DIAGONAL], -50.0, 50.0))
    L[_LOWER] = values
    return link_of_pseudo_inertia(L @ L.T)


def consistent_parameters(robot: Robot, base: BaseParameters, beta: np.ndarray,
                          std_error: np.ndarray) -> np.ndarray:
    """Standard parameters pi (12 n) that are physically consistent, reproduce beta
    within its standard errors where possible, and keep the URDF's values elsewhere.
    Only the links and friction among the identified (base and dependent) columns move."""
    n = robot.n
    nominal = robot.parameters()
    free = np.union1d(base.base, base.dependent)
    links = sorted({int(k) // 10 for k in free if k < 10 * n})
    friction = np.array([k for k in free if k >= 10 * n])
    sigma = np.maximum(std_error, 1e-6 * np.maximum(np.abs(beta), 1e-3))
    prior_scale = np.maximum(np.abs(nominal), 1e-3)

    def unpack(x: np.ndarray) -> np.ndarray:
        pi = nominal.copy()
        for j, i in enumerate(links):
            pi[10 * i:10 * i + 10] = _link(x[10 * j:10 * j + 10])
        pi[friction] = x[10 * len(links):]
        return pi

    def residual(x: np.ndarray) -> np.ndarray:
        pi = unpack(x)
        return np.concatenate([(base.project(pi) - beta) / sigma,
                               PRIOR_WEIGHT * (pi - nominal)[free] / prior_scale[free]])

    start = np.concatenate([*(_log_cholesky(nominal[10 * i:10 * i + 10]) for i in links),
                            np.maximum(nominal[friction], 0.0)])
    lower = np.concatenate([np.full(10 * len(links), -np.inf), np.zeros(len(friction))])
    # friction from the base estimate directly: its columns are always base columns
    for k, column in enumerate(friction):
        if column in base.base:
            start[10 * len(links) + k] = max(beta[list(base.base).index(column)], 0.0)
    result = scipy.optimize.least_squares(residual, start, bounds=(lower, np.inf),
                                          x_scale="jac", max_nfev=2000)
    return unpack(result.x)


def write_identified_urdf(robot: Robot, pi: np.ndarray, path: Path, comment: str) -> None:
    """The robot's URDF with each body's identified inertial on the joint's child link
    (links merged into that body lose theirs: the body's inertial holds them) and
    <dynamics damping="viscous" friction="Coulomb"/> on each joint."""
    tree = parse_urdf(robot.source)  # as read_urdf parsed it: no entity, no DTD
    root = tree.getroot()
    root.insert(0, etree.Comment(f" {comment.replace('--', '- -')} "))
    links = {link.get("name"): link for link in root.findall("link")}
    joints = {joint.get("name"): joint for joint in root.findall("joint")}
    n = robot.n
    for i, joint in enumerate(robot.joints):
        mass, com, inertia = body_inertial(pi[10 * i:10 * i + 10])
        check_inertia(inertia, f"identified link {joint.child_link!r}")
        for name in joint.merged_links:
            for element in links[name].findall("inertial"):
                links[name].remove(element)
        link = links[joint.child_link]
        for element in link.findall("inertial"):
            link.remove(element)
        inertial = etree.SubElement(link, "inertial")
        etree.SubElement(inertial, "origin", xyz=" ".join(f"{x:.12g}" for x in com), rpy="0 0 0")
        etree.SubElement(inertial, "mass", value=f"{mass:.12g}")
        etree.SubElement(inertial, "inertia", **{
            key: f"{inertia[r, c]:.12g}" for key, (r, c) in
            {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2),
             "izz": (2, 2)}.items()})
        element = joints[joint.name]
        for dynamics in element.findall("dynamics"):
            element.remove(dynamics)
        etree.SubElement(element, "dynamics", damping=f"{pi[10 * n + 2 * i]:.12g}",
                         friction=f"{pi[10 * n + 2 * i + 1]:.12g}")
    tree.write(str(path), xml_declaration=True, encoding="utf-8", pretty_print=True)
