"""Joint maps: which joint of a skeleton plays which part of a human body.

Found in three steps, each filling what the one before left open:

1. a user's map (role -> joint name; :func:`read_joint_map` reads JSON or TOML files);
2. the names (:mod:`.names`), resolved along each limb so that the roles come in body order;
3. the topology: the hips are the joint where the legs and the spine part (three long
   branches), the spine branch is the one where arms and a neck part again (with no arms: the
   one left when the two branches most alike in length are taken as legs), the chest is where
   the arms leave it (with no arms: the neck's parent), the neck branch is the shortest of the
   chest's branches. Along a limb, the joints
   at one place (zero-length joints such as CMU's ``LHipJoint``) count once; the hand or foot is
   the first place at least two segments out whose remaining chain is short (under 0.75 of the
   segment before: fingers, toes), the two segments before it are the upper and lower limb, and
   a third one before those on an arm is the clavicle.

Lengths used are bone lengths, which no rest pose changes: T, A, crouched and Bandai-Namco's
all-bones-along-X rest poses map alike. Joints with no role (twist bones, fingers, extra spine or
neck segments, zero-length joints, ends) are listed as unmapped, never an error.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._utils.tokens import listed, shown
from ..errors import MocapError
from ..motion import Skeleton
from .mapcheck import check_joint_map, check_spine
from .names import ARM_ROLES, LEG_ROLES, label, words

SIDES = ("left", "right")
CENTRE_ROLES = ("hips", "chest", "neck", "head")
SIDED_ROLES = tuple(f"{side}_{role}" for side in SIDES for role in ARM_ROLES + LEG_ROLES)
ROLES = CENTRE_ROLES + SIDED_ROLES
# Roles a skeleton must have for anything to be mapped onto it.
REQUIRED = ("hips", "chest", "head") + tuple(f"{s}_{r}" for s in SIDES for r in ("upper_leg", "lower_leg", "foot"))
_ARM_CORE = ("upper_arm", "forearm", "hand")

_LONG = 0.1  # a branch is long when it reaches this share of the skeleton's largest reach
_SHORT_END = 0.75  # the chain left after a hand or foot is under this share of the segment before


@dataclass(frozen=True)
class JointMap:
    """``joints``: role (:data:`ROLES`) -> joint index, for the roles found; ``spine``: the joints
    from just above the hips up to the chest, in order (the chest last); ``how``: role -> how it
    was found (``"map"``, ``"name"``, ``"name+topology"`` when both agree, ``"topology"``);
    ``unmapped``: the joints with no role."""

    names: tuple[str, ...]
    joints: dict[str, int]
    spine: tuple[int, ...]
    how: dict[str, str] = field(default_factory=dict)

    def __getitem__(self, role: str) -> int:
        try:
            return self.joints[role]
        except KeyError:
            raise MocapError(f"the skeleton has no {role.replace('_', ' ')} in its joint map") from None

    def get(self, role: str) -> int | None:
        return self.joints.get(role)

    def __contains__(self, role: str) -> bool:
        return role in self.joints

    @property
    def unmapped(self) -> tuple[int, ...]:
        used = set(self.joints.values()) | set(self.spine)
        return tuple(j for j in range(len(self.names)) if j not in used)

    def as_names(self) -> dict[str, object]:
        """Role -> joint name (``"spine"``: the list of names), the form of a map file."""
        out: dict[str, object] = {role: self.names[self.joints[role]] for role in ROLES if role in self.joints}
        out["spine"] = [self.names[j] for j in self.spine]
        return out

    def confidence(self) -> float:
        """Share of the roles found by names and topology together, or given by a map (0-1)."""
        sure = sum(1 for role in self.joints if self.how.get(role) in ("map", "name+topology"))
        return sure / max(len(self.joints), 1)


# -- reading a user's map ---------------------------------------------------------------------


def read_joint_map(path) -> dict[str, object]:
    """A map file: JSON or TOML (by extension; ``.toml`` for TOML), a table of role -> joint
    name, and ``spine`` -> a list of names. Roles are :data:`ROLES` (``shoulder`` is accepted for
    ``clavicle``). Raises :class:`MocapError` naming the file and what was wrong."""
    from .._utils.files import read_input

    path = Path(path)
    text = read_input(path).decode("utf-8", errors="replace")
    try:
        if path.suffix.lower() == ".toml":
            data = _toml(text)
        else:
            data = json.loads(text)
    except (ValueError, RecursionError) as error:  # RecursionError: nested past Python's stack
        raise MocapError(f"{path}: not a valid joint map ({_said(error)})") from None
    return map_table(data, path)


def map_table(data: object, path) -> dict[str, object]:
    """A joint map's table (as a map file holds it) checked: role -> joint name, ``spine`` -> a
    list of names; errors name ``path``."""
    if not isinstance(data, dict):
        raise MocapError(f"{path}: a joint map is a table of role -> joint name, got {type(data).__name__}")
    out: dict[str, object] = {}
    for key, value in data.items():
        role = str(key).replace("shoulder", "clavicle")
        if role == "spine":
            if not (isinstance(value, list) and value and all(isinstance(v, str) for v in value)):
                raise MocapError(f"{path}: 'spine' must be a list of joint names, from the hips up")
        elif role not in ROLES:
            raise MocapError(f"{path}: unknown role {shown(str(key))}; roles are spine, {', '.join(ROLES)}")
        elif not isinstance(value, str):
            raise MocapError(f"{path}: role {shown(str(key))} must name one joint, got {shown(repr(value))}")
        out[role] = value
    return out


def _said(error: Exception) -> str:
    return "nested too deeply" if isinstance(error, RecursionError) else str(error)


def _toml(text: str) -> dict:
    try:
        import tomllib  # Python 3.11+
    except ImportError:  # pragma: no cover - Python < 3.11
        import tomli as tomllib  # type: ignore[no-redef]
    return tomllib.loads(text)


# -- finding a map ------------------------------------------------------------------------------


def find_joint_map(skeleton: Skeleton, user_map: dict[str, object] | None = None, pose=None) -> JointMap:
    """The joint map of ``skeleton``: ``user_map`` (role -> joint name, as read by
    :func:`read_joint_map`) first, then names, then topology (see the module's notes). ``pose``
    (world positions ``[J, 3]`` of a posed frame, in the file's axes) tells left from right where
    names do not; without it, the rest pose is used.

    Raises :class:`MocapError` naming the roles that could not be found and how to give them.
    Commands read a skeleton's map once, from its :class:`~expressive_mocap.body.Body`.
    """
    if user_map:
        return _with_user_map(skeleton, user_map, pose)
    return _Finder(skeleton, None if pose is None else np.asarray(pose, dtype=np.float64).reshape(-1, 3)).run({})


def _with_user_map(skeleton: Skeleton, user_map: dict[str, object], pose) -> JointMap:
    given: dict[str, object] = {}
    for role, value in user_map.items():
        if role == "spine":
            given[role] = tuple(skeleton.index(str(n)) for n in value)  # type: ignore[attr-defined]
        else:
            given[role] = skeleton.index(str(value))
    return _Finder(skeleton, None if pose is None else np.asarray(pose, dtype=np.float64)).run(given)


class _Finder:
    def __init__(self, skeleton: Skeleton, pose: np.ndarray | None):
        self.skeleton = skeleton
        self.names = skeleton.names
        self.parents = skeleton.parents
        self.children: list[list[int]] = [[] for _ in self.names]
        for j in range(1, len(self.names)):
            self.children[int(self.parents[j])].append(j)
        self.bone = np.linalg.norm(skeleton.offsets, axis=1)
        self.reach = self._reaches()
        if not self.reach.max() > 0:
            raise MocapError("cannot map the skeleton: every bone has zero length (all its joints at one place)")
        self.scale = float(self.reach.max())
        self.eps = 1e-6 * self.scale
        self.labels = [label(n) for n in self.names]
        self.pose = skeleton.rest_positions()[0] if pose is None else pose
        self.how: dict[str, str] = {}

    def _reaches(self) -> np.ndarray:
        """Longest path of bone lengths from each joint to the end of its subtree (End Sites included)."""
        reach = np.zeros(len(self.names))
        for j, offset in self.skeleton.end_sites:
            reach[j] = max(reach[j], float(np.linalg.norm(offset)))
        for j in range(len(self.names) - 1, 0, -1):
            parent = int(self.parents[j])
            reach[parent] = max(reach[parent], self.bone[j] + reach[j])
        return reach

    def _long(self, joint: int) -> list[int]:
        return [c for c in self.children[joint] if self.bone[c] + self.reach[c] >= _LONG * self.scale]

    def _subtree(self, joint: int) -> list[int]:
        out, stack = [], [joint]
        while stack:
            j = stack.pop()
            out.append(j)
            stack.extend(self.children[j])
        return out

    def _main_path(self, joint: int) -> list[int]:
        path = [joint]
        while self.children[path[-1]]:
            path.append(max(self.children[path[-1]], key=lambda c: self.bone[c] + self.reach[c]))
        return path

    def _fail(self, what: str) -> MocapError:
        return MocapError(
            f"cannot tell which joint is the {what}: give it in a joint map file (JSON or TOML, "
            f'role -> joint name, e.g. {{"hips": "pelvis"}}; --map FILE on the command line); joints '
            f"are: {listed(self.names)}"
        )

    # -- the body's trunk

    def _hips(self, given: dict) -> int:
        if "hips" in given:
            return given["hips"]
        branching = next((j for j in range(len(self.names)) if len(self._long(j)) >= 3), None)
        named = [j for j, lab in enumerate(self.labels) if "hips" in lab.roles and len(self._long(j)) >= 3]
        if len(named) == 1:
            self.how["hips"] = "name+topology" if named[0] == branching else "name"
            return named[0]
        if branching is None:
            raise self._fail("hips (no joint has three long branches: two legs and a spine)")
        self.how["hips"] = "topology"
        return branching

    def _trunk(self, hips: int, given: dict) -> tuple[int, list[int]]:
        """The hips' spine branch child and its two leg branch children: the legs by name, else
        the spine is the branch where arms and a neck part (or, with no arms, the one left when
        the two most alike in length are taken as the legs)."""
        branches = self._long(hips)
        if len(branches) < 3:
            raise self._fail("legs (the hips have fewer than two long branches besides the spine)")
        named = [c for c in branches if any("upper_leg" in self.labels[j].roles for j in self._subtree(c))]
        if len(named) == 2:
            rest = [c for c in branches if c not in named]
            return max(rest, key=lambda c: len(self._subtree(c))), named
        forked = [c for c in branches if any(len(self._long(j)) >= 3 for j in self._subtree(c))]
        if len(forked) == 1:
            others = sorted((c for c in branches if c != forked[0]), key=lambda c: -(self.bone[c] + self.reach[c]))
            return forked[0], others[:2]
        length = {c: self.bone[c] + self.reach[c] for c in branches}
        pairs = [(a, b) for i, a in enumerate(branches) for b in branches[i + 1 :]]
        first, second = min(pairs, key=lambda pair: abs(length[pair[0]] - length[pair[1]]))
        legs = [first, second]
        rest = [c for c in branches if c not in legs]
        return max(rest, key=lambda c: len(self._subtree(c))), legs

    def _chest(self, spine_child: int, hips: int) -> tuple[int, list[int]]:
        """The joint where the arms leave the spine, and its long branches. A skeleton without
        arms: the joint two below the end of the spine's chain (the neck's parent)."""
        path = self._main_path(spine_child)
        for j in path:
            branches = self._long(j)
            if len(branches) >= 3:
                return j, branches
        if len(path) >= 3 and not any(len(self._long(j)) >= 2 for j in path):
            real = [j for j in path if self.skeleton.channels[j] and not _is_end(self.names[j])]
            if len(real) >= 3:
                chest = real[-3]
                return chest, [path[path.index(chest) + 1]]
        raise self._fail("chest (no joint on the spine has three long branches: two arms and a neck)")

    # -- limbs

    def _groups(self, path: list[int]) -> list[list[int]]:
        """The path's joints grouped by place: a zero-length joint joins the group before it."""
        groups: list[list[int]] = []
        for j in path:
            if groups and self.bone[j] <= self.eps:
                groups[-1].append(j)
            else:
                groups.append([j])
        return groups

    def _limb_topology(self, path: list[int], roles: tuple[str, ...]) -> dict[str, int]:
        """Topology's guess for a limb's roles (see the module's notes)."""
        groups = self._groups(path)
        firsts = [g[0] for g in groups]
        segments = [self.bone[g[0]] for g in groups[1:]]  # segment k ends at group k + 1
        for k in range(2, len(groups)):
            remaining = sum(segments[k:]) + self.reach[groups[-1][-1]]
            if remaining < _SHORT_END * segments[k - 1]:
                break
        else:
            return {}
        guess = {"upper": firsts[k - 2], "lower": firsts[k - 1], "end": firsts[k]}
        if roles == LEG_ROLES:
            out = {"upper_leg": guess["upper"], "lower_leg": guess["lower"], "foot": guess["end"]}
            if k + 1 < len(groups):
                out["toes"] = firsts[k + 1]
            return out
        out = {"upper_arm": guess["upper"], "forearm": guess["lower"], "hand": guess["end"]}
        if k >= 3:
            out["clavicle"] = firsts[k - 3]
        elif path[0] != guess["upper"]:
            out["clavicle"] = path[0]
        return out

    def _limb_names(self, path: list[int], roles: tuple[str, ...]) -> dict[str, int]:
        """The most joints of ``path`` whose names fit ``roles`` in body order (earliest joints first)."""

        # best[i][r]: (roles named, minus the sum of their joints' places, pairs) over path[i:] and
        # roles[r:], filled from the ends (a loop, not recursion: a chain may be 10,000 joints long).
        n, m = len(path), len(roles)
        nothing: tuple[int, int, tuple[tuple[str, int], ...]] = (0, 0, ())
        best = [[nothing] * (m + 1) for _ in range(n + 1)]
        for i in range(n - 1, -1, -1):
            for r in range(m - 1, -1, -1):
                options = [best[i + 1][r], best[i][r + 1]]  # skip the joint, skip the role
                if roles[r] in self.labels[path[i]].roles:
                    count, places, pairs = best[i + 1][r + 1]
                    options.append((count + 1, places - i, ((roles[r], path[i]),) + pairs))
                best[i][r] = max(options, key=lambda o: (o[0], o[1]))  # most roles, earliest joints
        return dict(best[0][0][2])

    def _limb(self, start: int, roles: tuple[str, ...], side: str, found: dict, given: dict) -> None:
        path = self._main_path(start)
        by_name = self._limb_names(path, roles)
        by_topology = self._limb_topology(path, roles)
        by_name = self._settled(by_name, by_topology)
        if "toes" in by_topology and self.labels[by_topology["toes"]].part == "heel":
            # A heel hangs behind the ankle, where no toe points: the foot's own joint stands in.
            del by_topology["toes"]
        for role in roles:
            key = f"{side}_{role}"
            if key in given:
                found[key], self.how[key] = given[key], "map"
            elif role in by_name:
                found[key] = by_name[role]
                self.how[key] = "name+topology" if by_topology.get(role) == by_name[role] else "name"
            elif role in by_topology and not _out_of_order(by_topology[role], role, roles, by_name, path):
                found[key], self.how[key] = by_topology[role], "topology"

    def _settled(self, by_name: dict[str, int], by_topology: dict[str, int]) -> dict[str, int]:
        """``by_name`` with each joint whose name fits several roles given the one topology gives
        it, where that is one of them: a "Foot" is the ankle where the leg ends with it or with a
        fore-foot, ball or heel the names do not tell, the toes on SMPL, after its "ankle"."""
        topology_role = {j: role for role, j in by_topology.items()}
        out = dict(by_name)
        for role, j in by_name.items():
            settled = topology_role.get(j)
            if settled and settled != role and settled in self.labels[j].roles and settled not in by_name:
                del out[role]
                out[settled] = j
        return out

    def _side(self, start: int, other: int, centre: int) -> str:
        """Which side the branch ``start`` is on: its names, else the pose (left = up x forward)."""
        for j in self._subtree(start):
            if self.labels[j].side:
                return self.labels[j].side
        pose = self.pose
        up = pose[self.chest] - pose[self.hips_joint]
        # Forward: where the toes point (the last two joints of each leg).
        toes = [self._main_path(c)[-2:] for c in self.legs]
        forward = np.mean([pose[t[-1]] - pose[t[0]] for t in toes], axis=0)
        forward -= up * (forward @ up) / max(up @ up, 1e-30)
        left = np.cross(up, forward)
        return "left" if (pose[self._far(start)] - pose[self._far(other)]) @ left > 0 else "right"

    def _far(self, start: int) -> int:
        return self._main_path(start)[min(2, len(self._main_path(start)) - 1)]

    def run(self, given: dict) -> JointMap:
        found: dict[str, int] = {}
        for role in CENTRE_ROLES + SIDED_ROLES:
            if role in given:
                self.how[role] = "map"
        hips = self._hips(given)
        self.hips_joint = hips
        self.scale = (
            float(self.reach[hips]) or self.scale
        )  # the body's size, not the root's (which may sit on the floor)
        found["hips"] = hips
        spine_child, legs = self._trunk(hips, given)
        self.legs = legs
        if "spine" in given:
            spine = list(given["spine"])
            check_spine(self.skeleton, hips, tuple(spine))
            chest = spine[-1]
            arms_and_neck = self._long(chest)
            if not arms_and_neck:
                raise self._fail(f"chest (the spine given ends at {shown(self.names[chest])}, where no neck leaves)")
        else:
            chest, arms_and_neck = self._chest(spine_child, hips)
            spine = _between(self.parents, hips, chest)
        self.chest = chest
        found["chest"] = given.get("chest", chest)
        self.how.setdefault(
            "chest", "topology" if not any("spine" in self.labels[j].roles for j in spine) else "name+topology"
        )
        neck_branch = next(
            (c for c in arms_and_neck if any("head" in self.labels[j].roles for j in self._subtree(c))),
            min(arms_and_neck, key=lambda c: self.bone[c] + self.reach[c]),
        )
        arms = [c for c in arms_and_neck if c != neck_branch]
        arms = sorted(arms, key=lambda c: -(self.bone[c] + self.reach[c]))[:2]
        self._head(neck_branch, found, given)
        for limbs, roles in ((legs, LEG_ROLES), (arms, ARM_ROLES)):
            if len(limbs) < 2:
                continue
            sides = [self._side(limbs[0], limbs[1], hips), self._side(limbs[1], limbs[0], hips)]
            if sides[0] == sides[1]:
                raise self._fail(f"left and right {'leg' if roles == LEG_ROLES else 'arm'} (both read as {sides[0]})")
            for start, side in zip(limbs, sides):
                self._limb(start, roles, side, found, given)
        missing = [r for r in REQUIRED if r not in found]
        for side in SIDES:  # an arm is all there or not at all
            if any(f"{side}_{r}" in found for r in _ARM_CORE) and not all(f"{side}_{r}" in found for r in _ARM_CORE):
                missing += [f"{side}_{r}" for r in _ARM_CORE if f"{side}_{r}" not in found]
        if missing:
            raise self._fail(", ".join(m.replace("_", " ") for m in missing))
        how = {role: self.how.get(role, "topology") for role in found}
        check_joint_map(self.skeleton, found, tuple(spine))
        return JointMap(self.names, found, tuple(spine), how)

    def _head(self, neck_branch: int, found: dict, given: dict) -> None:
        path = self._main_path(neck_branch)
        named = [j for j in path if "head" in self.labels[j].roles]
        real = [j for j in path if self.skeleton.channels[j] and not _is_end(self.names[j])]
        by_topology = (real or path)[-1]
        if "head" in given:
            found["head"] = given["head"]
        elif named:
            found["head"] = named[0]
            self.how["head"] = "name+topology" if named[0] == by_topology else "name"
        else:
            found["head"], self.how["head"] = by_topology, "topology"
        if "neck" in given:
            found["neck"] = given["neck"]
        elif path[0] != found["head"]:
            found["neck"] = path[0]
            self.how["neck"] = "name+topology" if "neck" in self.labels[path[0]].roles else "topology"


def _is_end(name: str) -> bool:
    return any(w in ("end", "nub", "top", "site", "tip") for w in words(name))


def _out_of_order(joint: int, role: str, roles: tuple[str, ...], by_name: dict[str, int], path: list[int]) -> bool:
    """Whether topology's ``joint`` for ``role`` would break the body order of the roles names found."""
    at = path.index(joint)
    for other, j in by_name.items():
        if j == joint:
            return True
        before = roles.index(other) < roles.index(role)
        if before != (path.index(j) < at):
            return True
    return False


def _between(parents: np.ndarray, top: int, bottom: int) -> list[int]:
    """Joints from just below ``top`` down to ``bottom``, in order from the top."""
    chain = [bottom]
    while int(parents[chain[-1]]) != top:
        chain.append(int(parents[chain[-1]]))
        if chain[-1] < 0:
            raise MocapError("the chest does not hang below the hips")
    return list(reversed(chain))


__all__ = [
    "CENTRE_ROLES",
    "REQUIRED",
    "ROLES",
    "SIDED_ROLES",
    "JointMap",
    "find_joint_map",
    "map_table",
    "read_joint_map",
]
