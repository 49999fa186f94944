"""Surfaces (points, triangles) of the visual shapes in their owner's frame,
and of a beam's section outline."""
import pathlib
import tempfile

import numpy as np

from .scene import OPTIONAL, SHAPES, VisualError, color, evaluate, orientation, vector

SEGMENTS = 24  # around a round shape


def revolve(profile, segments=SEGMENTS):
    """Surface of revolution about z of a profile [(r, z)] from bottom to top."""
    angles = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    points, rings = [], []
    for r, z in profile:
        if r == 0:
            rings.append([len(points)] * segments)
            points.append((0, 0, z))
        else:
            rings.append(list(range(len(points), len(points) + segments)))
            points += [(r * np.cos(a), r * np.sin(a), z) for a in angles]
    triangles = []
    for lower, upper in zip(rings[:-1], rings[1:]):
        for k in range(segments):
            a, b, c, d = lower[k], lower[(k + 1) % segments], upper[(k + 1) % segments], upper[k]
            triangles += [t for t in ((a, b, c), (a, c, d)) if len(set(t)) == 3]
    return np.array(points, float), np.array(triangles, int)


def box(size):
    corners = np.array([[i, j, k] for i in (-0.5, 0.5) for j in (-0.5, 0.5) for k in (-0.5, 0.5)]) * size
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return corners, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])


def capsule(radius, length, segments=SEGMENTS):
    arc = np.linspace(-np.pi / 2, np.pi / 2, segments // 2 + 1)
    bottom = [(radius * np.cos(a), -length / 2 + radius * np.sin(a)) for a in arc[:segments // 4 + 1]]
    top = [(radius * np.cos(a), length / 2 + radius * np.sin(a)) for a in arc[segments // 4:]]
    return revolve([(0.0, -length / 2 - radius)] + bottom[1:] + top[:-1] + [(0.0, length / 2 + radius)], segments)


def mesh_file(name, meshes, path):
    """Triangles of an STL or OBJ file carried in the FMU (resources/visual/)."""
    import meshio
    data = meshes.get(pathlib.PurePosixPath(name).name)
    if data is None:
        raise VisualError(f"{path}.file: '{name}' is not in the FMU's resources/visual/ (pack the scene again)")
    suffix = pathlib.PurePosixPath(name).suffix.lower()
    with tempfile.NamedTemporaryFile(suffix=suffix) as f:
        f.write(data)
        f.flush()
        m = meshio.read(f.name)
    triangles = []
    for block in m.cells:
        if block.type == "triangle":
            triangles.append(block.data)
        elif block.type == "quad":
            q = block.data
            triangles += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
    if not triangles:
        raise VisualError(f"{path}.file: '{name}' has no triangles or quads")
    return np.asarray(m.points, float)[:, :3], np.vstack(triangles)


def shape_surface(item, path, params, meshes):
    """(points in the owner's frame, triangles, colour) of one visual item."""
    shape = item.get("shape")
    if shape not in SHAPES:
        raise VisualError(f"{path}.shape: expected one of {', '.join(SHAPES)}, got {shape!r}")
    unknown = set(item) - SHAPES[shape] - OPTIONAL - {"shape"}
    missing = SHAPES[shape] - set(item)
    if unknown or missing:
        raise VisualError(f"{path}: a {shape} takes {', '.join(sorted(SHAPES[shape]))} "
                          f"(and {', '.join(sorted(OPTIONAL))}); " +
                          (f"unknown {sorted(unknown)}" if unknown else f"missing {sorted(missing)}"))

    def positive(key):
        v = evaluate(item[key], params, f"{path}.{key}")
        if not v > 0:
            raise VisualError(f"{path}.{key}: expected a positive length, got {v:g}")
        return v

    if shape == "box":
        size = vector(item["size"], params, path + ".size")
        if not np.all(size > 0):
            raise VisualError(f"{path}.size: expected three positive lengths")
        points, triangles = box(size)
    elif shape == "sphere":
        r = positive("radius")
        a = np.linspace(-np.pi / 2, np.pi / 2, SEGMENTS // 2 + 1)
        points, triangles = revolve([(r * np.cos(x) if abs(x) < np.pi / 2 - 1e-9 else 0.0, r * np.sin(x)) for x in a])
    elif shape == "cylinder":
        r, h = positive("radius"), positive("length")
        points, triangles = revolve([(0.0, -h / 2), (r, -h / 2), (r, h / 2), (0.0, h / 2)])
    elif shape == "capsule":
        points, triangles = capsule(positive("radius"), positive("length"))
    else:
        points, triangles = mesh_file(item["file"], meshes, path)
        if "scale" in item:
            points = points * positive("scale")
    R = orientation(item["orientation"], params, path + ".orientation") if "orientation" in item else np.eye(3)
    offset = vector(item["position"], params, path + ".position") if "position" in item else np.zeros(3)
    return points @ R.T + offset, triangles, color(item.get("color"), path + ".color")


def section_outline(section, visual, params, path, default_size, segments=16):
    """Outline of a beam's section in its (y, z) plane: the visual section if
    given, else the physical section's shape, else a circle of default_size."""
    s = (visual or {}).get("section") or section
    shape = s.get("shape") if isinstance(s, dict) else None
    where = f"{path}.visual.section" if (visual or {}).get("section") else f"{path}.section"
    a = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    if shape == "rectangle":
        b, h = evaluate(s["b"], params, where + ".b"), evaluate(s["h"], params, where + ".h")
        return np.array([[-b / 2, -h / 2], [b / 2, -h / 2], [b / 2, h / 2], [-b / 2, h / 2]])
    if shape in ("circle", "tube"):
        r = evaluate(s["d"], params, where + ".d") / 2 if shape == "circle" else evaluate(s["ro"], params, where + ".ro")
        return np.column_stack([r * np.cos(a), r * np.sin(a)])
    if shape is not None:
        raise VisualError(f"{where}.shape: expected rectangle, circle or tube")
    return np.column_stack([default_size / 2 * np.cos(a), default_size / 2 * np.sin(a)])
