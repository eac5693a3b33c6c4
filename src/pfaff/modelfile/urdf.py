"""URDF robot descriptions as pfaff systems: ``load_urdf(path)`` → :class:`pfaff.System`.

A URDF file is a tree of links joined by joints. Each movable joint (``revolute``,
``continuous``, ``prismatic``) becomes one coordinate named after it; ``fixed`` joints add none.
Each link with an ``<inertial>`` of positive mass becomes a rigid body whose attitude is the
link frame, a :class:`~pfaff.attitude.Rotation` C(q) that the links of a chain share
coordinates through; its inertia (given in the inertial frame, ``<inertial><origin rpy>``) is
rotated into the link frame, C_link I_link C_linkᵀ with I_link = R_in I R_inᵀ. Gravity is
``gravity`` (9.81) along −z. A joint's ``<dynamics damping="d">`` is the Rayleigh function
R = ½ d q̇².

Every link's mass, mass-centre offset and inertia entries are parameters named ``<link>.mass``,
``<link>.com_x`` … ``<link>.com_z``, ``<link>.ixx``, ``<link>.ixy``, … ``<link>.izz`` (joint
damping ``<joint>.damping``), the file's values being ``system.urdf_values`` so that
``system.equations().compile(system.urdf_values)`` is the file's robot.

Frames follow the URDF specification: a joint's ``<origin xyz rpy>`` places the joint frame in
the parent link frame (R = Rz(yaw) Ry(pitch) Rx(roll)); the child link frame is the joint frame
turned about (revolute, continuous) or moved along (prismatic) the unit ``<axis>`` by q.

The file is untrusted: its size is capped before it is read, a DOCTYPE or ENTITY declaration is
refused before parsing (no entity expansion), the standard library's ``xml.etree.ElementTree``
parses the rest, links and joints are counted, every number must be finite. ``visual``,
``collision`` and ``material`` elements are ignored. Refused, each by name: ``mimic`` joints,
``planar`` and ``floating`` joints, ``transmission`` elements, several roots, a link with two
parents, missing or invalid numbers.
"""

from __future__ import annotations

import math
import os
import re
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import sympy as sp

from pfaff.api.system import System
from pfaff.core.errors import ModelError
from pfaff.core.files import file_path, read_capped
from pfaff.core.keywords import checked_keywords
from pfaff.core.stack import outside_pfaff
from pfaff.core.symbols import coordinates as make_coordinates
from pfaff.core.symbols import t
from pfaff.mechanics.attitude import Rotation

MAX_BYTES = 10_000_000
MAX_ELEMENTS = 1000
GRAVITY = 9.81
MOVABLE = ("revolute", "continuous", "prismatic")
REFUSED_JOINTS = ("planar", "floating")
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
EXACT_ANGLE_TOL = 1e-12


@dataclass
class _Inertial:
    mass: float
    com: tuple[float, float, float]
    rpy: tuple[float, float, float]
    inertia: dict[str, float]


@dataclass
class _Link:
    name: str
    inertial: _Inertial | None


@dataclass
class _Joint:
    name: str
    kind: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    limits: tuple[float, float] | None
    damping: float


@dataclass
class _Robot:
    name: str
    links: dict[str, _Link]
    joints: dict[str, _Joint]
    root: str = ""
    order: list[str] = field(default_factory=list)  # joints, parents before children


@checked_keywords
def load_urdf(
    path: str | os.PathLike,
    fixed_base: bool = True,
    *,
    enforce_limits: bool = False,
    restitution: float = 0.0,
) -> System:
    """Read a URDF file into a :class:`pfaff.System`.

    Parameters
    ----------
    path : str or PathLike
        The URDF file (at most ``MAX_BYTES``; at most ``MAX_ELEMENTS`` links and joints).
    fixed_base : bool
        True: the root link is fixed. False: the root link floats, with six more coordinates
        ``<root>_x``, ``<root>_y``, ``<root>_z`` (position of its frame) and ``<root>_roll``,
        ``<root>_pitch``, ``<root>_yaw`` (C = Rz(yaw) Ry(pitch) Rx(roll); singular at
        pitch = ±π/2).
    enforce_limits : bool
        True: each joint limit becomes two unilateral constraints (``"<joint> lower"``
        q − lower ≥ 0 and ``"<joint> upper"`` upper − q ≥ 0; see
        :meth:`pfaff.System.add_unilateral_constraint`): the joint stops there, with an impact.
    restitution : float
        Newton's e of those stops, in [0, 1] (default 0: a stop that does not bounce).

    Returns
    -------
    System
        With the attributes ``urdf_values`` (dict: parameter name → the file's value, and
        ``gravity``; also the parameters' defaults, so ``compile()`` needs no values), ``urdf_coordinates`` (dict: joint name → coordinate, in the system's
        order), ``urdf_links`` (dict: link name → the prefix of its parameter names),
        ``joint_limits`` (dict: joint name → (lower, upper), revolute and prismatic joints) and
        ``urdf_name`` (the robot's name).

    Raises
    ------
    ModelError
        Naming the file and the element (link or joint) at fault.

    Examples
    --------
    >>> import pathlib, tempfile, pfaff
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "pendulum.urdf"
    >>> _ = path.write_text('''<robot name="pendulum">
    ...   <link name="base"/>
    ...   <link name="bob"><inertial><origin xyz="0 0 -1"/><mass value="2"/>
    ...     <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
    ...   <joint name="hinge" type="continuous"><parent link="base"/><child link="bob"/>
    ...     <axis xyz="0 1 0"/></joint>
    ... </robot>''')
    >>> arm = pfaff.load_urdf(path)
    >>> model = arm.equations().compile(arm.urdf_values)
    >>> round(float(model.accelerations(0.0, [0.5], [0.0])[0][0]), 6)  # -g sin(q) / L
    -4.703165
    """
    for arg, flag in (("fixed_base", fixed_base), ("enforce_limits", enforce_limits)):
        if not isinstance(flag, bool):
            raise ModelError(f"`{arg}` must be True or False, got {flag!r:.40}")
    if isinstance(restitution, bool) or not isinstance(restitution, int | float):
        raise ModelError(f"`restitution` must be a number in [0, 1], got {restitution!r:.40}")
    if not 0.0 <= restitution <= 1.0:
        raise ModelError(f"`restitution` must be in [0, 1], got {restitution!r:.40}")
    source = str(path)
    robot = parse_urdf(_read(path), source)
    try:
        system = _build(robot, fixed_base)
        if enforce_limits:
            _stops(system, float(restitution))
    except ModelError as e:
        raise ModelError(f"{source}: {e}") from e
    return system


def _stops(system: System, restitution: float) -> None:
    """The joint limits as unilateral constraints (``enforce_limits=True``)."""
    for joint, (lower, upper) in system.joint_limits.items():
        if not lower < upper:
            raise ModelError(
                f"joint `{joint}`: its limits ({lower:g}, {upper:g}) leave it no room to move: "
                "enforce_limits needs lower < upper"
            )
        q = system.urdf_coordinates[joint]
        system.add_unilateral_constraint(q - lower, name=f"{joint} lower", restitution=restitution)
        system.add_unilateral_constraint(upper - q, name=f"{joint} upper", restitution=restitution)


def _read(path: str | os.PathLike) -> str:
    """The file's text, its size capped and DOCTYPE/ENTITY declarations refused."""
    p = file_path(path)
    text = read_capped(p, MAX_BYTES, f"the URDF file {p}", ModelError)
    upper = text.upper()
    for decl in ("<!DOCTYPE", "<!ENTITY"):
        if decl in upper:
            raise ModelError(
                f"{p}: the URDF file has a {decl[2:]} declaration; refused (no DTDs or entities "
                "in an untrusted file)"
            )
    return text


def parse_urdf(text: str, source: str = "<urdf>") -> _Robot:
    """Parse URDF text into links and joints, checking the tree (one root, one parent each)."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise ModelError(f"{source}: not well-formed XML ({e})") from e
    if root.tag != "robot":
        raise ModelError(f"{source}: the root element is <{root.tag}>, not <robot>")
    found = root.find(".//transmission")
    if found is not None:
        raise ModelError(
            f"{source}: transmission `{found.get('name', '?')}`: <transmission> elements are not "
            "supported (actuation is the user's: add torques or inputs to the system)"
        )
    link_elems, joint_elems = root.findall("link"), root.findall("joint")
    for what, elems in (("links", link_elems), ("joints", joint_elems)):
        if len(elems) > MAX_ELEMENTS:
            raise ModelError(f"{source}: {len(elems)} {what}, more than {MAX_ELEMENTS}; refused")
    try:
        links = _unique([_link(e) for e in link_elems], "link")
        joints = _unique([_joint(e) for e in joint_elems], "joint")
    except ModelError as e:
        raise ModelError(f"{source}: {e}") from e
    robot = _Robot(root.get("name", ""), links, joints)
    try:
        _tree(robot)
    except ModelError as e:
        raise ModelError(f"{source}: {e}") from e
    return robot


def _unique(items: list, kind: str) -> dict:
    out: dict = {}
    for item in items:
        if item.name in out:
            raise ModelError(f"{kind} `{item.name}` is defined twice")
        out[item.name] = item
    return out


def _name(elem: ET.Element, kind: str) -> str:
    name = elem.get("name")
    if not name or not name.strip():
        raise ModelError(f"a <{kind}> has no name")
    if len(name) > 200:
        raise ModelError(f"a <{kind}> name is longer than 200 characters: {name[:40]!r}…")
    return name


def _numbers(
    elem: ET.Element | None, attr: str, count: int, what: str, default: tuple | None = None
) -> tuple[float, ...]:
    """``count`` finite numbers from attribute ``attr`` of ``elem`` (``default`` when absent)."""
    text = elem.get(attr) if elem is not None else None
    if text is None:
        if default is None:
            tag = elem.tag if elem is not None else "element"
            raise ModelError(f"{what}: <{tag}> has no `{attr}`")
        return default
    parts = text.split()
    if len(parts) != count or len(text) > 400:
        raise ModelError(f"{what}: `{attr}` must be {count} number(s), got {text[:60]!r}")
    try:
        values = tuple(float(s) for s in parts)
    except ValueError as e:
        raise ModelError(f"{what}: `{attr}` is not a number: {text[:60]!r}") from e
    if not all(math.isfinite(v) for v in values):
        raise ModelError(f"{what}: `{attr}` must be finite, got {text[:60]!r}")
    return values


def _origin(elem: ET.Element, what: str) -> tuple[tuple, tuple]:
    o = elem.find("origin")
    if o is None:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    return _numbers(o, "xyz", 3, what, (0.0, 0.0, 0.0)), _numbers(o, "rpy", 3, what, (0.0,) * 3)


def _link(elem: ET.Element) -> _Link:
    name = _name(elem, "link")
    what = f"link `{name}`"
    ine = elem.find("inertial")
    if ine is None:
        return _Link(name, None)
    (mass,) = _numbers(ine.find("mass"), "value", 1, f"{what} <mass>")
    if mass < 0:
        raise ModelError(f"{what}: negative mass {mass:g}")
    inertia_elem = ine.find("inertia")
    if inertia_elem is None and mass > 0:
        raise ModelError(f"{what}: <inertial> has a mass but no <inertia>")
    inertia = {
        k: (_numbers(inertia_elem, k, 1, f"{what} <inertia>")[0] if mass > 0 else 0.0)
        for k in INERTIA_KEYS
    }
    com, rpy = _origin(ine, f"{what} <inertial><origin>")
    if mass > 0:
        _check_inertia(inertia, what)
    return _Link(name, _Inertial(mass, com, rpy, inertia))


def _check_inertia(inertia: dict, what: str) -> None:
    """Positive semidefinite (point masses and thin rods allowed), principal moments satisfying
    the triangle inequality."""
    import numpy as np

    i = inertia
    mat = np.array(
        [
            [i["ixx"], i["ixy"], i["ixz"]],
            [i["ixy"], i["iyy"], i["iyz"]],
            [i["ixz"], i["iyz"], i["izz"]],
        ]
    )
    a, b, c = np.linalg.eigvalsh(mat)
    tol = 1e-9 * max(c, 1e-300)
    if not a >= -tol or a + b < c - tol:
        raise ModelError(
            f"{what}: the inertia is not that of a body (principal moments "
            f"{a:.6g}, {b:.6g}, {c:.6g}: must not be negative, each at most the sum of the others)"
        )


def _joint(elem: ET.Element) -> _Joint:
    name = _name(elem, "joint")
    what = f"joint `{name}`"
    kind = elem.get("type", "")
    if elem.find("mimic") is not None:
        raise ModelError(f"{what}: <mimic> joints are not supported")
    if kind in REFUSED_JOINTS:
        raise ModelError(f"{what}: {kind} joints are not supported")
    if kind not in (*MOVABLE, "fixed"):
        raise ModelError(
            f"{what}: unknown type {kind[:40]!r} (revolute, continuous, prismatic, fixed)"
        )
    ends = []
    for tag in ("parent", "child"):
        e = elem.find(tag)
        if e is None or not e.get("link"):
            raise ModelError(f"{what}: no <{tag} link=...>")
        ends.append(e.get("link"))
    xyz, rpy = _origin(elem, f"{what} <origin>")
    axis = _numbers(elem.find("axis"), "xyz", 3, f"{what} <axis>", (1.0, 0.0, 0.0))
    if kind in MOVABLE and math.hypot(*axis) < 1e-9:
        raise ModelError(f"{what}: the axis is zero")
    limits = None
    lim = elem.find("limit")
    if kind in ("revolute", "prismatic"):
        if lim is None:
            raise ModelError(f"{what}: a {kind} joint needs a <limit>")
        (lo,) = _numbers(lim, "lower", 1, f"{what} <limit>", (0.0,))
        (hi,) = _numbers(lim, "upper", 1, f"{what} <limit>", (0.0,))
        limits = (lo, hi)
    dyn = elem.find("dynamics")
    (damping,) = _numbers(dyn, "damping", 1, f"{what} <dynamics>", (0.0,))
    (friction,) = _numbers(dyn, "friction", 1, f"{what} <dynamics>", (0.0,))
    if damping < 0:
        raise ModelError(f"{what}: negative damping {damping:g}")
    if friction != 0:
        warnings.warn(
            f"{what}: Coulomb friction {friction:g} is ignored", stacklevel=outside_pfaff()
        )
    return _Joint(name, kind, ends[0], ends[1], xyz, rpy, axis, limits, damping)


def _tree(robot: _Robot) -> None:
    """One root, each link one parent, all links reachable: ``robot.root`` and ``robot.order``."""
    parent_of: dict[str, str] = {}
    children: dict[str, list[str]] = {name: [] for name in robot.links}
    for j in robot.joints.values():
        for end in (j.parent, j.child):
            if end not in robot.links:
                raise ModelError(f"joint `{j.name}`: link `{end}` is not defined")
        if j.child in parent_of:
            raise ModelError(
                f"link `{j.child}` has two parent joints, `{parent_of[j.child]}` and `{j.name}` "
                "(a closed loop; URDF describes trees)"
            )
        parent_of[j.child] = j.name
        children[j.parent].append(j.name)
    roots = [name for name in robot.links if name not in parent_of]
    if len(roots) != 1:
        listed = ", ".join(f"`{r}`" for r in roots[:10]) or "none"
        raise ModelError(f"the links must form one tree with one root; roots: {listed}")
    robot.root = roots[0]
    stack, seen = [robot.root], {robot.root}
    while stack:
        link = stack.pop(0)
        for jn in children[link]:
            robot.order.append(jn)
            child = robot.joints[jn].child
            seen.add(child)
            stack.append(child)
    unreached = [name for name in robot.links if name not in seen]
    if unreached:
        raise ModelError(f"links not connected to root `{robot.root}` (a loop): {unreached[:10]}")


# --- building the system -------------------------------------------------------------------


def identifier(name: str, taken: set[str]) -> str:
    """A Python identifier for a URDF name (non-word characters → ``_``), unique in ``taken``."""
    base = re.sub(r"\W", "_", name, flags=re.ASCII) or "_"
    if base[0].isdigit() or base.startswith("_"):
        base = "j" + base
    out, k = base, 1
    while out in taken or out == "t":
        k += 1
        out = f"{base}_{k}"
    taken.add(out)
    return out


def _number(v: float) -> sp.Expr:
    return sp.Integer(int(v)) if float(v).is_integer() else sp.Float(v)


def _cos_sin(a: float) -> tuple[sp.Expr, sp.Expr]:
    """cos a, sin a; exact at multiples of π/2 (to 1e-12), floats otherwise."""
    k = a / (math.pi / 2)
    if abs(k - round(k)) < EXACT_ANGLE_TOL:
        return sp.cos(round(k) * sp.pi / 2), sp.sin(round(k) * sp.pi / 2)
    return sp.Float(math.cos(a)), sp.Float(math.sin(a))


def _rpy(rpy: tuple) -> sp.Matrix:
    """Rz(yaw) Ry(pitch) Rx(roll) of the URDF specification."""
    (cr, sr), (cp, sp_), (cy, sy) = (_cos_sin(a) for a in rpy)
    rx = sp.Matrix([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = sp.Matrix([[cp, 0, sp_], [0, 1, 0], [-sp_, 0, cp]])
    rz = sp.Matrix([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz * ry * rx


def _unit(axis: tuple) -> sp.Matrix:
    norm = math.sqrt(sum(a * a for a in axis))
    if abs(norm - 1) < 1e-12:
        return sp.Matrix([_number(a) for a in axis])
    return sp.Matrix([_number(a / norm) for a in axis])


def _about(axis: sp.Matrix, q: sp.Expr) -> sp.Matrix:
    """Rotation by q about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = sp.Matrix([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return sp.eye(3) + sp.sin(q) * k + (1 - sp.cos(q)) * k * k


def _coordinates(names: list[str]) -> tuple:
    if not names:
        return ()
    made = make_coordinates(" ".join(names))
    return made if isinstance(made, tuple | list) else (made,)


def _euler_base(root: str, taken: set[str]) -> tuple[list, sp.Matrix, sp.Matrix]:
    names = [identifier(f"{root}_{s}", taken) for s in ("x", "y", "z", "roll", "pitch", "yaw")]
    q = list(_coordinates(names))
    rot = _about(sp.Matrix([0, 0, 1]), q[5]) * _about(sp.Matrix([0, 1, 0]), q[4])
    return q, rot * _about(sp.Matrix([1, 0, 0]), q[3]), sp.Matrix(q[:3])


def _euler_omega(angles: list) -> sp.Matrix:
    """Body angular velocity of C = Rz(yaw) Ry(pitch) Rx(roll)."""
    roll, pitch, _ = angles
    dr, dp, dy = (a.diff(t) for a in angles)
    return sp.Matrix(
        [
            dr - sp.sin(pitch) * dy,
            sp.cos(roll) * dp + sp.sin(roll) * sp.cos(pitch) * dy,
            -sp.sin(roll) * dp + sp.cos(roll) * sp.cos(pitch) * dy,
        ]
    )


def _build(robot: _Robot, fixed_base: bool) -> System:
    taken: set[str] = set()
    joint_ids = {j: identifier(j, taken) for j in robot.order if robot.joints[j].kind in MOVABLE}
    coords = dict(zip(joint_ids, _coordinates(list(joint_ids.values())), strict=True))
    poses: dict[str, tuple[sp.Matrix, sp.Matrix]] = {}
    base_q: list = []
    if fixed_base:
        poses[robot.root] = (sp.eye(3), sp.zeros(3, 1), sp.zeros(3, 1), sp.zeros(3, 1))
    else:
        base_q, rot, pos = _euler_base(robot.root, taken)
        vel = rot.T * sp.Matrix([p.diff(t) for p in pos])
        poses[robot.root] = (rot, pos, _euler_omega(base_q[3:]), vel)
    for jn in robot.order:
        poses[robot.joints[jn].child] = _child_pose(robot.joints[jn], poses, coords.get(jn))
    if not coords and not base_q:
        raise ModelError(f"robot `{robot.name}` has no movable joint")
    system = System([*base_q, *coords.values()])
    gravity = sp.Symbol("gravity")
    values: dict[str, float] = {"gravity": GRAVITY}
    prefixes: dict[str, str] = {}
    for name, link in robot.links.items():
        rot, pos, omega, vel = poses[name]
        moves = any(e.has(t) for e in (*rot, *pos))
        if link.inertial is None or link.inertial.mass == 0 or not moves:
            continue
        prefix = identifier(name, taken)
        prefixes[name] = prefix
        attitude = _ChainRotation(rot, omega, source=f"link `{name}`")
        _add_link(system, link, prefix, (attitude, pos, vel), gravity, values)
    for jn, q in coords.items():
        joint = robot.joints[jn]
        if joint.damping > 0:
            d = sp.Symbol(f"{joint_ids[jn]}.damping")
            values[d.name] = joint.damping
            qd = q.diff(t)
            system.add_dissipation(d * qd**2 / 2, name=f"{jn} damping")
    system.urdf_name = robot.name
    system.urdf_values = values
    used = {p.name for p in system.parameters}
    system.set_parameter_defaults({k: v for k, v in values.items() if k in used})
    system.urdf_coordinates = dict(coords)
    system.urdf_links = prefixes
    system.joint_limits = {
        jn: robot.joints[jn].limits for jn in coords if robot.joints[jn].limits is not None
    }
    return system


class _ChainRotation(Rotation):
    """A link frame's Rotation whose body angular velocity is known from the chain,
    ω_child = R_jᵀ ω_parent + a q̇ (R_j the joint's turn, a its unit axis), instead of being
    derived from CᵀĊ: the same vector, without differentiating a product of many rotations.
    ``centre_velocity`` (body components) is set once the link's mass centre is known."""

    def __init__(self, dcm: sp.Matrix, omega: sp.Matrix, source: str = "") -> None:
        self._chain_omega = omega
        super().__init__(dcm, source)

    def _omega_of(self, c: sp.Matrix) -> sp.Matrix:
        return sp.Matrix(self._chain_omega)


def _child_pose(joint: _Joint, poses: dict, q: sp.Expr | None) -> tuple:
    """The child link frame: C and origin (inertial components), body angular velocity and
    origin velocity (child-frame components), each from the parent's, unexpanded:
    ω = Rᵀ ω_p + a q̇, v = Rᵀ (v_p + ω_p × p) (+ a q̇ for a prismatic joint), R the joint's
    turn, p its offset in the parent frame, a its unit axis."""
    rot_p, pos_p, omega_p, vel_p = poses[joint.parent]
    turn = _rpy(joint.rpy)
    offset = sp.Matrix([_number(v) for v in joint.xyz])
    pos = pos_p + rot_p * offset
    axis = _unit(joint.axis)
    omega = turn.T * omega_p
    vel = turn.T * (vel_p + omega_p.cross(offset))
    if joint.kind in ("revolute", "continuous"):
        spin = _about(axis, q)
        turn = turn * spin
        omega = spin.T * omega + axis * q.diff(t)
        vel = spin.T * vel
    elif joint.kind == "prismatic":
        pos = pos + rot_p * turn * axis * q
        vel = vel + axis * q.diff(t)
    return rot_p * turn, pos, omega, vel


def _add_link(
    system: System,
    link: _Link,
    prefix: str,
    frame: tuple[_ChainRotation, sp.Matrix, sp.Matrix],
    gravity: sp.Symbol,
    values: dict,
) -> None:
    """The link's body (``frame``: its Rotation, origin and origin velocity) and its weight."""
    attitude, pos, vel = frame
    ine = link.inertial
    mass = sp.Symbol(f"{prefix}.mass")
    com = sp.Matrix([sp.Symbol(f"{prefix}.com_{a}") for a in "xyz"])
    ent = {k: sp.Symbol(f"{prefix}.{k}") for k in INERTIA_KEYS}
    values[mass.name] = ine.mass
    values.update({s.name: v for s, v in zip(com, ine.com, strict=True)})
    values.update({ent[k].name: ine.inertia[k] for k in INERTIA_KEYS})
    inertia = sp.Matrix(
        [
            [ent["ixx"], ent["ixy"], ent["ixz"]],
            [ent["ixy"], ent["iyy"], ent["iyz"]],
            [ent["ixz"], ent["iyz"], ent["izz"]],
        ]
    )
    if any(ine.rpy):
        r_in = _rpy(ine.rpy)
        inertia = (r_in * inertia * r_in.T).applyfunc(sp.expand)
    attitude.centre_velocity = vel + attitude.angular_velocity.cross(com)
    centre = pos + sp.Matrix(attitude.dcm) * com
    system.add_rigid_body(mass, inertia, list(centre), attitude, name=link.name)
    system.add_potential_energy(mass * gravity * centre[2], name=f"{link.name} gravity")
