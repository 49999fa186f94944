"""The mechanism as surfaces at each output time: bodies posed with their
visual shapes from their position and orientation outputs, flexible bodies
as their section swept through the exposed nodes (node position and
orientation outputs), with velocity at the points and section forces at
the cells."""
import dataclasses
import re

import numpy as np

from .geometry import revolve, section_outline, shape_surface
from .scene import VisualError, color, evaluate, parameter_values, quaternion_matrix, read_scene, vector, visual_list

DEFAULT_COLOR = (0.62, 0.66, 0.72)
BEAM_COLOR = (0.85, 0.45, 0.20)


@dataclasses.dataclass
class Part:
    """A rigid surface (points in its owner's frame) or one beam segment."""
    name: str
    points: np.ndarray
    triangles: np.ndarray
    color: tuple
    body: str = ""              # owner body (rigid parts)
    flex: str = ""              # owner flexible body (beam segments)
    nodes: tuple = ()           # the segment's end nodes
    frames: tuple = ()          # section frame at each end relative to the node frame
    elements: tuple = ()        # elements the segment spans: the first exposed one gives its section forces


def body_names(scene):
    return [b["name"] for b in scene.get("bodies") or []]


def node_pattern(flex):
    return re.compile(re.escape(flex) + r"\.node(\d+)\.position\.x$")


def required_outputs(scene):
    """Output patterns the drawing reads (positions, orientations, velocities, section forces, energy)."""
    patterns = []
    for b in body_names(scene):
        patterns += [f"{b}.position.*", f"{b}.orientation.*", f"{b}.velocity.*", f"{b}.angular_velocity.*"]
    for f in scene.get("flexible_bodies") or []:
        patterns += [f"{f['name']}.node*.*", f"{f['name']}.element*.end1.*", f"{f['name']}.strain_energy"]
    return patterns


def design_nodes(flex, params, path):
    """Node positions and frames in the design configuration, and the elements."""
    if "beam" in flex:
        line = flex["beam"]
        start, end = vector(line["start"], params, path + ".beam.start"), vector(line["end"], params, path + ".beam.end")
        n = int(evaluate(line["elements"], params, path + ".beam.elements"))
        y_hint = vector(line["section_y"], params, path + ".beam.section_y") if "section_y" in line else np.r_[0, 1.0, 0]
        x = (end - start) / np.linalg.norm(end - start)
        y = y_hint - y_hint.dot(x) * x
        frame = np.column_stack([x, y / np.linalg.norm(y), np.cross(x, y / np.linalg.norm(y))])
        nodes = [start + (end - start) * i / n for i in range(n + 1)]
        return nodes, [frame] * (n + 1), [(i, i + 1) for i in range(n)]
    nodes = [vector(p, params, f"{path}.nodes[{i}]") for i, p in enumerate(flex["nodes"])]
    return nodes, [np.eye(3)] * len(nodes), [tuple(e) for e in flex["elements"]]


def section_frame(a, b, y_hint):
    x = (b - a) / np.linalg.norm(b - a)
    y = y_hint - y_hint.dot(x) * x
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def beam_parts(flex, path, params, exposed, default_size):
    """One swept segment per pair of exposed nodes that an element (or, on a
    beam line, a run of elements) joins."""
    nodes, frames, elements = design_nodes(flex, params, path)
    visual = flex.get("visual") or {}
    if not isinstance(visual, dict):
        raise VisualError(f"{path}.visual: expected an object (color, section)")
    outline = section_outline(flex["section"], visual, params, path, default_size)
    col = color(visual.get("color"), path + ".visual.color") or BEAM_COLOR
    y_hint = np.r_[0, 1.0, 0]
    if "section_y" in flex:
        y_hint = vector(flex["section_y"], params, path + ".section_y")
    if "beam" in flex:
        line = sorted(exposed)
        pairs = [(a, b, tuple(range(a, b))) for a, b in zip(line[:-1], line[1:])]
    else:
        pairs = [(a, b, (e,)) for e, (a, b) in enumerate(elements) if a in exposed and b in exposed]
    parts = []
    m = len(outline)
    ring = np.column_stack([np.zeros(m), outline])  # section points in the section frame
    tube = [t for k in range(m) for t in ((k, (k + 1) % m, m + (k + 1) % m), (k, m + (k + 1) % m, m + k))]
    for a, b, e in pairs:
        F0 = frames[a] if "beam" in flex else section_frame(nodes[a], nodes[b], y_hint)
        parts.append(Part(f"{flex['name']}[{a}-{b}]", np.vstack([ring, ring]), np.array(tube), col,
                          flex=flex["name"], nodes=(a, b), frames=(frames[a].T @ F0, frames[b].T @ F0), elements=e))
    return parts


def check_visuals(fmu, parameters=None):
    """Every body's visual made into a surface once: a bad entry fails
    before the run, naming its JSON path."""
    scene, meshes = read_scene(fmu)
    params = parameter_values(scene, parameters)
    for i, b in enumerate(scene.get("bodies") or []):
        for item, where in visual_list(b, f"bodies[{i}]"):
            shape_surface(item, where, params, meshes)
    for i, f in enumerate(scene.get("flexible_bodies") or []):
        beam_parts(f, f"flexible_bodies[{i}]", params, set(), 1.0)


class Drawing:
    """Surfaces of a scene, posed from a Result that holds the outputs of required_outputs()."""

    def __init__(self, fmu, result):
        scene, meshes = read_scene(fmu)
        params = parameter_values(scene, result.parameters)
        self.result = result
        gravity = [evaluate(g, params, f"gravity[{i}]") for i, g in enumerate(scene.get("gravity", [0, 0, 0]))]
        self.up = "xyz"[int(np.argmax(np.abs(gravity)))] if np.any(gravity) else "z"  # drawn upwards
        v = result.values
        positions = [np.array([v[f"{b}.position.{c}"][0] for c in "xyz"]) for b in body_names(scene)
                     if f"{b}.position.x" in v]
        positions += [np.array([v[n][0], v[n.replace(".x", ".y")][0], v[n.replace(".x", ".z")][0]])
                      for n in v if re.search(r"\.node\d+\.position\.x$", n)]
        extent = np.ptp(np.array(positions), axis=0).max() if len(positions) > 1 else 1.0
        self.default_size = 0.04 * (extent if extent > 0 else 1.0)
        self.parts = []
        self.missing = []
        for i, b in enumerate(scene.get("bodies") or []):
            path = f"bodies[{i}]"
            if f"{b['name']}.orientation.w" not in v:
                self.missing.append(b["name"])
                continue
            items = visual_list(b, path)
            if not items:  # no visual: a small sphere marks the body frame
                p, t = revolve([(0.0, -1.0)] + [(np.cos(a), np.sin(a)) for a in np.linspace(-1.3, 1.3, 7)] + [(0.0, 1.0)])
                self.parts.append(Part(b["name"], p * self.default_size / 2, t, DEFAULT_COLOR, body=b["name"]))
            for item, where in items:
                p, t, c = shape_surface(item, where, params, meshes)
                self.parts.append(Part(b["name"], p, t, c or DEFAULT_COLOR, body=b["name"]))
        for i, f in enumerate(scene.get("flexible_bodies") or []):
            exposed = {int(node_pattern(f["name"]).match(n).group(1)) for n in v if node_pattern(f["name"]).match(n)}
            if len(exposed) < 2:
                self.missing.append(f["name"])
                continue
            self.parts += beam_parts(f, f"flexible_bodies[{i}]", params, exposed, self.default_size / 2)
        if not self.parts:
            raise ValueError(f"nothing to draw: {', '.join(self.missing) or 'the scene'} expose no pose; list the "
                             "bodies in the scene's \"outputs\" and two or more nodes of a flexible body in its "
                             "\"outputs\" (\"nodes\": \"all\" for its deflected shape)")

    def _pose(self, owner, k):
        v = self.result.values
        p = np.array([v[f"{owner}.position.{c}"][k] for c in "xyz"])
        R = quaternion_matrix([v[f"{owner}.orientation.{c}"][k] for c in "wxyz"])
        return p, R

    def _rates(self, owner, k):
        v = self.result.values
        get = (lambda q: np.array([v[f"{owner}.{q}.{c}"][k] for c in "xyz"]) if f"{owner}.{q}.x" in v
               else np.full(3, np.nan))
        return get("velocity"), get("angular_velocity")

    def frame(self, k):
        """Points, triangles, point data and cell data at output k."""
        points, triangles, velocity, cells = [], [], [], {"part": [], "color": [], "section_force": [],
                                                        "section_moment": [], "strain_energy": []}
        offset = 0
        for index, part in enumerate(self.parts):
            if part.body:
                p0, R = self._pose(part.body, k)
                v0, w = self._rates(part.body, k)
                pts = part.points @ R.T + p0
                vel = v0 + np.cross(w, pts - p0)
            else:
                pts, vel = self._segment(part, k)
            n_cells = len(part.triangles)
            force, moment, energy = self._section_data(part, k)
            points.append(pts)
            velocity.append(vel)
            triangles.append(part.triangles + offset)
            offset += len(pts)
            cells["part"] += [index] * n_cells
            cells["color"] += [part.color] * n_cells
            cells["section_force"] += [force] * n_cells
            cells["section_moment"] += [moment] * n_cells
            cells["strain_energy"] += [energy] * n_cells
        return (np.vstack(points), np.vstack(triangles), {"velocity": np.vstack(velocity)},
                {key: np.array(val, float) for key, val in cells.items()})

    def _segment(self, part, k):
        m = len(part.points) // 2
        pts, vel = [], []
        for end, node in enumerate(part.nodes):
            owner = f"{part.flex}.node{node}"
            p0, R = self._pose(owner, k)
            v0, w = self._rates(owner, k)
            ring = (part.points[end * m:(end + 1) * m] @ (R @ part.frames[end]).T) + p0
            pts.append(ring)
            vel.append(v0 + np.cross(w, ring - p0))
        return np.vstack(pts), np.vstack(vel)

    def _section_data(self, part, k):
        v = self.result.values
        nan3 = [np.nan] * 3
        energy = v.get(f"{part.flex}.strain_energy") if part.flex else None
        energy = float(energy[k]) if energy is not None else np.nan
        exposed = [e for e in part.elements if f"{part.flex}.element{e}.end1.force.x" in v]
        if not exposed:
            return nan3, nan3, energy
        stem = f"{part.flex}.element{exposed[0]}.end1"
        pick = lambda q: [float(v[f"{stem}.{q}.{c}"][k]) for c in "xyz"] if f"{stem}.{q}.x" in v else nan3
        return pick("force"), pick("moment"), energy
