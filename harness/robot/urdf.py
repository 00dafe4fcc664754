"""Reading a robot's URDF into the flat arrays of the C rigid-body model (rigid_body.h).

A URDF is accepted when it describes a serial chain of at most 12 revolute,
continuous or prismatic joints from a fixed base: fixed joints (and joints the
caller locks, at 0 or a given position) are merged into the moving body they hang from, and
branches that carry no moving joint (sensors, tool frames) are allowed.  Every
problem is a UrdfError whose message names the file and the joint or link: also a
document type declaration (entities are never expanded, so a file that declares
them would mean something else to another reader), a number beyond LARGEST in SI
units (no robot part has it, and products of such numbers overflow), and links or
joints that the tree from the root does not reach (a closed loop, a second tree).
Chains of any length are walked without recursion.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from lxml import etree

from ..inputs import xml_parser
from .layout import ParameterLayout, core_layout
from .native import core_defaults

MOVING_TYPES = {"revolute": 0, "continuous": 0, "prismatic": 1}  # -> RbJointType
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
LARGEST = 1e6  # [m, kg, kg m^2, rad, N m s/rad, N m]: a larger URDF number is refused
# [kg]: a link's mass is 0 (a massless link: legal URDF) or at least this.  The centre of
# mass is a quotient by the mass and the link's size sqrt(tr I / 2m): with every number
# within LARGEST, both stay far inside float64 above it (1e6 / 1e-20 = 1e26), while a
# mass at float64's edge (5e-324) turns them into infinities.  No robot part is lighter.
SMALLEST_MASS = 1e-20


class UrdfError(ValueError):
    """The URDF cannot be used; the message names the file and what is wrong."""


@dataclass
class ChainJoint:
    """One moving joint of the chain and the body it moves (all fixed links merged).

    xyz, rpy: the joint frame in the previous joint's frame (the base's for the
    first) at q = 0; link: the body's 10 standard parameters in the joint frame
    (m, m c, inertia about the frame origin: xx, xy, yy, xz, yz, zz)."""
    name: str
    kind: str                      # "revolute" or "prismatic" (continuous is revolute)
    child_link: str
    axis: np.ndarray
    xyz: np.ndarray
    rpy: np.ndarray
    link: np.ndarray
    damping: float = 0.0           # URDF <dynamics damping>: viscous
    friction: float = 0.0          # URDF <dynamics friction>: Coulomb
    merged_links: list[str] = field(default_factory=list)  # links fixed to the body
    #: each of the body's links (its own and the merged ones): its frame (R, p) in the
    #: joint frame, and whether it has mass (harness.robot.geometry bounds the centre of
    #: mass by their shapes)
    frames: dict[str, tuple[np.ndarray, np.ndarray, bool]] = field(default_factory=dict)


@dataclass
class Robot:
    """A serial chain read from a URDF."""
    name: str
    source: Path
    base_link: str
    joints: list[ChainJoint]
    locked: tuple[str, ...] = ()
    gravity: np.ndarray = field(default_factory=lambda: np.array(DEFAULT_GRAVITY))
    #: each locked joint's position (rad or m): 0 unless a position is given or logged
    locked_at: dict[str, float] = field(default_factory=dict)
    #: where each locked joint's position comes from: "given" (--lock JOINT=POSITION),
    #: "log" (the median of its log column, harness.robot.held_joints) or "default" (0)
    locked_from: dict[str, str] = field(default_factory=dict)
    #: each locked joint's URDF type ("revolute", "continuous", "prismatic" or "fixed")
    locked_kinds: dict[str, str] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.joints)

    @property
    def joint_names(self) -> list[str]:
        return [j.name for j in self.joints]

    def arrays(self) -> dict[str, np.ndarray]:
        """The flat arrays of rb_load (as FMU parameters would hold them)."""
        return {"types": np.array([MOVING_TYPES[j.kind] for j in self.joints], dtype=np.int32),
                "axis": np.array([j.axis for j in self.joints]),
                "xyz": np.array([j.xyz for j in self.joints]),
                "rpy": np.array([j.rpy for j in self.joints]),
                "link": np.array([j.link for j in self.joints]),
                "friction": np.array([[j.damping, j.friction] for j in self.joints]),
                "gravity": np.asarray(self.gravity, dtype=float)}

    def parameters(self) -> np.ndarray:
        """The nominal parameter vector pi (12 n) of the regressor."""
        a = self.arrays()
        return ParameterLayout(self.n).join(a["link"], a["friction"])

    def rigid_body(self, link: np.ndarray | None = None, friction: np.ndarray | None = None,
                   coulomb_velocity: float = 0.0):
        """The C model, with the URDF's parameters or the given ones."""
        from .native import RigidBody
        a = self.arrays()
        return RigidBody(a["types"], a["axis"], a["xyz"], a["rpy"],
                         a["link"] if link is None else link,
                         a["friction"] if friction is None else friction,
                         a["gravity"], coulomb_velocity)


# ---- geometry ------------------------------------------------------------------------

def rpy_matrix(rpy) -> np.ndarray:
    """URDF rotation: Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def matrix_rpy(R: np.ndarray) -> np.ndarray:
    """The inverse of rpy_matrix (roll = 0 at pitch = +-90 degrees)."""
    cos_pitch = np.hypot(R[0, 0], R[1, 0])
    pitch = np.arctan2(-R[2, 0], cos_pitch)
    if cos_pitch < 1e-12:
        return np.array([0.0, pitch, np.arctan2(-R[0, 1], R[1, 1])])
    return np.array([np.arctan2(R[2, 1], R[2, 2]), pitch, np.arctan2(R[1, 0], R[0, 0])])


def _skew(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def standard_parameters(mass: float, com: np.ndarray, inertia_com: np.ndarray) -> np.ndarray:
    """(m, m c, I about the origin as xx, xy, yy, xz, yz, zz) from mass, centre of
    mass and the 3x3 inertia about the centre of mass, all in one frame."""
    I = inertia_com - mass * _skew(com) @ _skew(com)
    return np.array([mass, *(mass * com), I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]])


def inertia_matrix(six) -> np.ndarray:
    xx, xy, yy, xz, yz, zz = six
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def body_inertial(link: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, centre of mass, 3x3 inertia about it) from 10 standard parameters; a
    massless body (m = 0, a URDF link without <inertial>) has its centre of mass at the
    origin and the inertia about it (zero for a link without inertial)."""
    mass = float(link[0])
    if mass == 0.0:
        return 0.0, np.zeros(3), inertia_matrix(link[4:])
    com = link[1:4] / mass
    return mass, com, inertia_matrix(link[4:]) + mass * _skew(com) @ _skew(com)


# ---- parsing ----------------------------------------------------------------------------

def attribute_floats(element, attribute: str, count: int, default: str,
                     where: str) -> np.ndarray:
    """The attribute's `count` numbers (`default` if the element or attribute is absent);
    UrdfError names anything else: not numbers, not finite, beyond LARGEST, subnormal."""
    text = element.get(attribute, default) if element is not None else default
    try:
        if "_" in text:  # Python's float() reads "1_0" as 10; an XML double has no "_"
            raise ValueError(text)
        values = np.array([float(x) for x in text.split()])
    except ValueError:
        raise UrdfError(f"{where}: {attribute}={text!r} is not {count} numbers") from None
    if values.size != count or not np.all(np.isfinite(values)):
        raise UrdfError(f"{where}: {attribute}={text!r} is not {count} finite numbers")
    tag = f"<{element.tag} {attribute}={text!r}>" if element is not None else attribute
    if np.any(np.abs(values) > LARGEST):
        raise UrdfError(f"{where}: {tag} holds a number beyond {LARGEST:g} (SI units): "
                        f"not a robot's")
    if np.any((values != 0) & (np.abs(values) < np.finfo(float).tiny)):
        # subnormal: at float64's edge, with few significant bits; 0 is written 0
        raise UrdfError(f"{where}: {tag} holds a number below {np.finfo(float).tiny:.3g} "
                        f"(subnormal in float64): write 0 or a meaningful value")
    return values


def origin_frame(element, where: str) -> tuple[np.ndarray, np.ndarray]:
    """(R, p) of an <origin> child (identity if absent)."""
    origin = element.find("origin")
    return (rpy_matrix(attribute_floats(origin, "rpy", 3, "0 0 0", where)),
            attribute_floats(origin, "xyz", 3, "0 0 0", where))


def _link_inertial(link, source: Path) -> tuple[float, np.ndarray, np.ndarray] | None:
    """(mass, centre of mass, inertia about it) in the link frame, validated; None if absent."""
    inertial = link.find("inertial")
    if inertial is None:
        return None
    where = f"{source}: link {link.get('name')!r} <inertial>"
    mass_element = inertial.find("mass")
    mass = (attribute_floats(mass_element, "value", 1, "", where)[0]
            if mass_element is not None else 0.0)
    if mass < 0:
        raise UrdfError(f"{where}: negative mass {mass}")
    if 0 < mass < SMALLEST_MASS:
        raise UrdfError(f"{where}: mass {mass:g} kg is below {SMALLEST_MASS:g} kg: write 0 "
                        f"for a massless link (or leave out <inertial>)")
    R, com = origin_frame(inertial, where)
    element = inertial.find("inertia")
    six = [attribute_floats(element, key, 1, "0", where)[0]
           for key in ("ixx", "ixy", "iyy", "ixz", "iyz", "izz")]
    inertia = inertia_matrix(six)
    check_inertia(inertia, where)
    return mass, com, R @ inertia @ R.T


def check_inertia(inertia: np.ndarray, where: str, tolerance: float = 1e-9) -> None:
    """Raise UrdfError unless the inertia about the centre of mass is positive
    semi-definite and its principal moments satisfy the triangle inequalities."""
    moments = np.linalg.eigvalsh(inertia)
    scale = max(abs(moments).max(), 1e-300)
    if moments[0] < -tolerance * scale:
        raise UrdfError(f"{where}: the inertia is not positive definite (principal moments "
                        f"{', '.join(f'{m:.6g}' for m in moments)})")
    if moments[0] + moments[1] < moments[2] - tolerance * scale:
        raise UrdfError(f"{where}: the principal moments {', '.join(f'{m:.6g}' for m in moments)} "
                        f"violate the triangle inequality (a + b >= c): no rigid body has them")


def parse_urdf(source: Path, remove_blank_text: bool = False):
    """The URDF's XML tree: no entity expanded, no DTD or network access; UrdfError if
    it does not parse or declares a document type (entities)."""
    parser = xml_parser(remove_blank_text=remove_blank_text)
    try:
        tree = etree.parse(str(source), parser)
    except OSError as error:
        raise UrdfError(f"{source}: cannot read ({error})") from None
    except etree.XMLSyntaxError as error:
        raise UrdfError(f"{source}: does not parse as XML ({error})") from None
    if tree.docinfo.doctype or tree.docinfo.internalDTD is not None or any(
            isinstance(node, etree._Entity) for node in tree.getroot().iter()):
        raise UrdfError(f"{source}: declares a document type or entities (<!DOCTYPE ...>, "
                        f"<!ENTITY ...>); a URDF has none: remove the declaration")
    return tree


def read_urdf(path: str | Path, locked: Sequence[str] | Mapping[str, float | None] = (),
              gravity=DEFAULT_GRAVITY, joints_used: Sequence[str] | None = None,
              origins: Mapping[str, str] | None = None) -> Robot:
    """Read and validate a URDF as a serial chain; `locked` joints are fixed at 0, or at
    the position (rad or m) a mapping gives each (None: 0, as for a sequence). `joints_used`
    (None: every moving joint not locked): the chain's moving joints, from the root
    outward; every other joint is fixed at 0, so that a branching robot (a mobile base's
    wheels, a second arm) reduces to the chain of one arm. `origins`: where a locked
    position comes from, by joint (a phrase for the message that refuses it)."""
    given = dict(locked) if isinstance(locked, Mapping) else dict.fromkeys(locked)
    positions = {name: 0.0 if value is None else float(value) for name, value in given.items()}
    locked = list(positions)
    source = Path(path)
    root = parse_urdf(source).getroot()
    if root.tag != "robot":
        raise UrdfError(f"{source}: not a URDF (the root element is <{root.tag}>, not <robot>)")
    links = {}
    for link in root.findall("link"):
        name = link.get("name")
        if not name or name in links:
            raise UrdfError(f"{source}: a link without a name or a duplicate link {name!r}")
        links[name] = link
        _link_inertial(link, source)  # every link's values meaningful, also where unused
    joints: dict[str, etree._Element] = {}
    parent_joint: dict[str, etree._Element] = {}
    for joint in root.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        parent, child = joint.find("parent"), joint.find("child")
        if not name or name in joints:
            raise UrdfError(f"{source}: a joint without a name or a duplicate joint {name!r}")
        if parent is None or child is None or parent.get("link") not in links \
                or child.get("link") not in links:
            raise UrdfError(f"{source}: joint {name!r} does not name an existing parent and "
                            f"child link")
        if kind not in MOVING_TYPES and kind != "fixed":
            raise UrdfError(f"{source}: joint {name!r} is of type {kind!r}; only revolute, "
                            f"continuous, prismatic and fixed joints are supported")
        if child.get("link") in parent_joint:
            raise UrdfError(f"{source}: link {child.get('link')!r} has two parent joints "
                            f"({parent_joint[child.get('link')].get('name')!r}, {name!r})")
        joints[name] = joint
        parent_joint[child.get("link")] = joint
    unknown = [name for name in locked if name not in joints]
    if unknown:
        raise UrdfError(f"{source}: locked joint(s) {', '.join(map(repr, unknown))} not in the "
                        f"URDF (its joints: {', '.join(joints)})")
    for name, position in positions.items():
        _check_lock_position(source, joints[name], position, (origins or {}).get(name))
    if joints_used is not None:
        locked = [*locked, *_others_locked(source, joints, list(joints_used), locked)]
    roots = [name for name in links if name not in parent_joint]
    if len(roots) != 1:
        raise UrdfError(f"{source}: expected one root link, found {len(roots)} "
                        f"({', '.join(roots[:5])})")
    _check_connected(source, roots[0], links, joints)
    positions.update((name, 0.0) for name in locked if name not in positions)
    chain = _Chain(source, links, joints, positions)
    chain.walk(roots[0])
    if not chain.joints:
        raise UrdfError(f"{source}: no revolute, continuous or prismatic joint")
    max_joints = core_defaults().max_joints
    if len(chain.joints) > max_joints:
        raise UrdfError(f"{source}: {len(chain.joints)} moving joints; at most {max_joints} are "
                        f"supported (name the chain's with --joints, or lock some with --lock)")
    if joints_used is not None and [j.name for j in chain.joints] != list(joints_used):
        raise UrdfError(f"{source}: --joints {','.join(joints_used)}: the chain from the root "
                        f"link meets them in the order {','.join(j.name for j in chain.joints)}"
                        f"; give them in that order (and map the log's columns with --columns)")
    robot = Robot(root.get("name", source.stem), source, roots[0], chain.joints, tuple(locked),
                  np.asarray(gravity, dtype=float), positions,
                  {name: "default" if given.get(name) is None else "given" for name in locked},
                  {name: joints[name].get("type") for name in locked})
    for joint in robot.joints:  # merged bodies: sums of bounded numbers, still finite?
        if not all(np.all(np.isfinite(x)) for x in (joint.xyz, joint.rpy, joint.link)):
            raise UrdfError(f"{source}: joint {joint.name!r}: its body's position or inertia "
                            f"is not finite")
    return robot


def joint_indices(names: Sequence[str], moving: Sequence[str], where: str) -> list[int]:
    """The positions in ``moving`` of the joints an option lists (``where``: the option
    and its value, for the message); UrdfError for a name that is not a moving joint or
    is given twice."""
    found: list[int] = []
    for name in names:
        if name not in moving:
            raise UrdfError(f"{where}: {name!r} is not a moving joint (the moving joints: "
                            f"{', '.join(moving)})")
        if moving.index(name) in found:
            raise UrdfError(f"{where}: {name!r} is named twice")
        found.append(moving.index(name))
    return found


def _check_lock_position(source: Path, joint, position: float,
                         origin: str | None = None) -> None:
    """A joint locked at a position other than 0 moves (a fixed joint has no position) and
    the position lies within its <limit> (a revolute or prismatic joint's, when given);
    `origin` says where the position comes from in the message."""
    where = f"{source}: joint {joint.get('name')!r}"
    said = f" ({origin})" if origin else ""
    if not np.isfinite(position):
        raise UrdfError(f"{where}: locked at {position!r}, not a finite position")
    if position == 0.0:
        return
    kind = joint.get("type")
    if kind not in MOVING_TYPES:
        raise UrdfError(f"{where} is fixed: it has no position to lock it at ({position:g})")
    limit = joint.find("limit")
    if kind == "continuous" or limit is None:
        return
    lower, upper = (attribute_floats(limit, key, 1, "0", where)[0] for key in ("lower", "upper"))
    if lower < upper and not lower <= position <= upper:
        unit = "m" if kind == "prismatic" else "rad"
        raise UrdfError(f"{where}: locked at {position:g} {unit}{said}, outside its limits "
                        f"[{lower:g}, {upper:g}] {unit}")


def _others_locked(source: Path, joints: dict, used: list[str], locked) -> list[str]:
    """The moving joints that ``used`` (--joints) leaves out; UrdfError for a name that is
    not a moving joint of the URDF, a repeat, or a joint also locked."""
    moving = [name for name, joint in joints.items() if joint.get("type") in MOVING_TYPES]
    listed = f"{source}: --joints {','.join(used)}"
    joint_indices(used, moving, listed)
    for name in used:
        if name in locked:
            raise UrdfError(f"{listed}: {name!r} is also locked (--lock)")
    return [name for name in moving if name not in used and name not in locked]


def _check_connected(source: Path, root: str, links: dict, joints: dict) -> None:
    """UrdfError naming the links that the tree from ``root`` does not reach (a closed
    loop of joints, or a second tree whose root has a parent)."""
    children: dict[str, list[str]] = {}
    for joint in joints.values():
        children.setdefault(joint.find("parent").get("link"), []).append(
            joint.find("child").get("link"))
    reached, stack = {root}, [root]
    while stack:
        for child in children.get(stack.pop(), []):
            if child not in reached:
                reached.add(child)
                stack.append(child)
    lost = [name for name in links if name not in reached]
    if lost:
        raise UrdfError(f"{source}: link(s) {', '.join(map(repr, lost[:5]))} are not reached "
                        f"from the root link {root!r}: the joints form a closed loop or a "
                        f"second tree; a URDF is one tree")


class _Chain:
    """Walks the kinematic tree from the root, merging fixed links into their body."""

    def __init__(self, source: Path, links: dict, joints: dict, locked: dict[str, float]):
        self.source, self.links, self.locked = source, links, locked  # name -> position
        self.children: dict[str, list] = {}
        for joint in joints.values():
            self.children.setdefault(joint.find("parent").get("link"), []).append(joint)
        self.joints: list[ChainJoint] = []
        self._reaching = self._links_reaching_moving()

    def moving(self, joint) -> bool:
        return joint.get("type") in MOVING_TYPES and joint.get("name") not in self.locked

    def _links_reaching_moving(self) -> set[str]:
        """The links with a moving joint below them: from every moving joint up to the
        root, iteratively (a chain of thousands of fixed links recursed too deep)."""
        parent_of = {joint.find("child").get("link"): joint.find("parent").get("link")
                     for joints in self.children.values() for joint in joints}
        reaching: set[str] = set()
        for joints in self.children.values():
            for joint in joints:
                if self.moving(joint):
                    link = joint.find("parent").get("link")
                    while link is not None and link not in reaching:
                        reaching.add(link)
                        link = parent_of.get(link)
        return reaching

    def reaches_moving(self, joint) -> bool:
        """The joint moves, or a joint below it does."""
        return self.moving(joint) or joint.find("child").get("link") in self._reaching

    def walk(self, root: str) -> None:
        # (link, the body it belongs to (None: the base), R, p of its frame in the body frame)
        stack: list[tuple[str, ChainJoint | None, np.ndarray, np.ndarray]] = \
            [(root, None, np.eye(3), np.zeros(3))]
        while stack:
            name, body, R, p = stack.pop()
            if body is not None:
                self._merge(body, self.links[name], R, p)
            onward = [j for j in self.children.get(name, []) if self.reaches_moving(j)]
            if len(onward) > 1:
                raise UrdfError(f"{self.source}: not a serial chain: link {name!r} branches into "
                                f"joints {', '.join(repr(j.get('name')) for j in onward)} that "
                                f"both lead to moving joints (name the chain's joints with "
                                f"--joints, or lock the joints of all but one branch)")
            for joint in self.children.get(name, []):
                where = f"{self.source}: joint {joint.get('name')!r}"
                Rj, pj = origin_frame(joint, where)
                R_child, p_child = R @ Rj, R @ pj + p
                child = joint.find("child").get("link")
                if self.moving(joint):
                    moved = self._moving_joint(joint, child, R_child, p_child, where)
                    stack.append((child, moved, np.eye(3), np.zeros(3)))
                else:
                    R_child, p_child = self._held(joint, R_child, p_child, where)
                    stack.append((child, body, R_child, p_child))

    def _held(self, joint, R: np.ndarray, p: np.ndarray, where: str
              ) -> tuple[np.ndarray, np.ndarray]:
        """The child frame (R, p) of a locked joint moved to its position (its <origin>
        frame at 0): a rotation or a translation along its axis."""
        position = self.locked.get(joint.get("name"), 0.0)
        if position == 0.0:
            return R, p
        axis = attribute_floats(joint.find("axis"), "xyz", 3, "1 0 0", where)
        if not np.linalg.norm(axis) > 1e-9:
            raise UrdfError(f"{where}: the axis is zero")
        axis = axis / np.linalg.norm(axis)
        if joint.get("type") == "prismatic":
            return R, p + R @ (axis * position)
        K = _skew(axis)  # Rodrigues' rotation by `position` about the axis
        return R @ (np.eye(3) + np.sin(position) * K + (1.0 - np.cos(position)) * K @ K), p

    def _moving_joint(self, joint, child: str, R: np.ndarray, p: np.ndarray,
                      where: str) -> ChainJoint:
        """The chain joint at (R, p) in the previous body's frame, appended to the chain."""
        axis = attribute_floats(joint.find("axis"), "xyz", 3, "1 0 0", where)
        if not np.linalg.norm(axis) > 1e-9:
            raise UrdfError(f"{where}: the axis is zero")
        dynamics = joint.find("dynamics")
        damping, friction = (attribute_floats(dynamics, key, 1, "0", where)[0]
                             for key in ("damping", "friction"))
        if damping < 0 or friction < 0:
            raise UrdfError(f"{where}: negative damping or friction in <dynamics>")
        if joint.find("mimic") is not None:
            raise UrdfError(f"{where}: mimics another joint; lock it (--lock {joint.get('name')})")
        kind = "prismatic" if joint.get("type") == "prismatic" else "revolute"
        body = ChainJoint(joint.get("name"), kind, child, axis / np.linalg.norm(axis), p,
                          matrix_rpy(R), np.zeros(core_layout().link_size), damping,
                          friction)
        self.joints.append(body)
        return body

    def _merge(self, body: ChainJoint, link, R: np.ndarray, p: np.ndarray) -> None:
        """Add the link's inertial (its frame at (R, p) in the body frame) to the body."""
        inertial = _link_inertial(link, self.source)
        if link.get("name") != body.child_link:
            body.merged_links.append(link.get("name"))
        body.frames[link.get("name")] = (R, p, inertial is not None and inertial[0] > 0)
        if inertial is None:
            return
        mass, com, inertia = inertial
        body.link = body.link + standard_parameters(mass, R @ com + p, R @ inertia @ R.T)
