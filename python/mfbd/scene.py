"""The packed scene (resources/scene.json) as the drawing tools need it:
its expressions evaluated with the run's parameter values, the optional
`visual` of bodies and flexible bodies checked and turned into surfaces."""
import ast
import json
import math
import pathlib
import re
import zipfile

import numpy as np

FUNCTIONS = {"sqrt": math.sqrt, "sin": math.sin, "cos": math.cos, "tan": math.tan, "asin": math.asin,
             "acos": math.acos, "atan": math.atan, "exp": math.exp, "log": math.log, "abs": abs,
             "min": min, "max": max, "_if": lambda c, a, b: a if c > 0 else b}
SHAPES = {"box": {"size"}, "cylinder": {"radius", "length"}, "sphere": {"radius"},
          "capsule": {"radius", "length"}, "mesh": {"file"}}
OPTIONAL = {"position", "orientation", "color", "scale"}


class VisualError(ValueError):
    """A bad visual entry, named by its JSON path."""


def read_scene(fmu):
    """The scene JSON packed in the FMU, and the mesh files beside it (name -> bytes)."""
    with zipfile.ZipFile(fmu) as z:
        scene = json.loads(z.read("resources/scene.json"))
        meshes = {pathlib.PurePosixPath(n).name: z.read(n) for n in z.namelist()
                  if n.startswith("resources/visual/") and not n.endswith("/")}
    return scene, meshes


def parameter_values(scene, overrides=None):
    values = {}
    for name, p in (scene.get("parameters") or {}).items():
        values[name] = float(p["value"] if isinstance(p, dict) else p)
    values.update({k: float(v) for k, v in (overrides or {}).items() if k in values})
    return values


def evaluate(value, params, path):
    """A number or an expression of the scene's grammar (+ - * / ^, functions, if, pi)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    if not isinstance(value, str):
        raise VisualError(f"{path}: expected a number or an expression, got {json.dumps(value)}")
    text = re.sub(r"\bif\s*\(", "_if(", value).replace("^", "**")
    try:
        return float(_eval(ast.parse(text, mode="eval").body, params))
    except (SyntaxError, KeyError, TypeError, ValueError, ZeroDivisionError) as e:
        raise VisualError(f"{path}: cannot evaluate \"{value}\": {e}") from None


def _eval(node, params):
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
        return node.value
    if isinstance(node, ast.Name):
        if node.id == "pi":
            return math.pi
        if node.id not in params:
            raise KeyError(f"unknown parameter '{node.id}'")
        return params[node.id]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        v = _eval(node.operand, params)
        return -v if isinstance(node.op, ast.USub) else v
    ops = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
           ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a ** b}
    if isinstance(node, ast.BinOp) and type(node.op) in ops:
        return ops[type(node.op)](_eval(node.left, params), _eval(node.right, params))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS:
        return FUNCTIONS[node.func.id](*[_eval(a, params) for a in node.args])
    raise ValueError("unsupported expression")


def vector(value, params, path, n=3):
    if not isinstance(value, list) or len(value) != n:
        raise VisualError(f"{path}: expected {n} numbers")
    return np.array([evaluate(v, params, f"{path}[{i}]") for i, v in enumerate(value)])


def frame_from_z(z, x_hint=None):
    """Columns x, y, z: x from x_hint (or world X, or world Y) off z."""
    z = z / np.linalg.norm(z)
    for hint in ([x_hint] if x_hint is not None else []) + [np.array([1.0, 0, 0]), np.array([0, 1.0, 0])]:
        x = hint - hint.dot(z) * z
        if np.linalg.norm(x) > 1e-6:
            x = x / np.linalg.norm(x)
            return np.column_stack([x, np.cross(z, x), z])
    raise VisualError("x_axis is parallel to z_axis")


def quaternion_matrix(q):
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def orientation(value, params, path):
    """The scene's orientation object: quaternion, z_axis (+ x_axis) or rotation_vector."""
    if not isinstance(value, dict):
        raise VisualError(f"{path}: expected an orientation object")
    if "quaternion" in value:
        return quaternion_matrix(vector(value["quaternion"], params, path + ".quaternion", 4))
    if "rotation_vector" in value:
        r = vector(value["rotation_vector"], params, path + ".rotation_vector")
        angle = np.linalg.norm(r)
        if angle < 1e-15:
            return np.eye(3)
        return quaternion_matrix(np.r_[math.cos(angle / 2), math.sin(angle / 2) * r / angle])
    if "z_axis" in value:
        x = vector(value["x_axis"], params, path + ".x_axis") if "x_axis" in value else None
        return frame_from_z(vector(value["z_axis"], params, path + ".z_axis"), x)
    raise VisualError(f"{path}: expected quaternion, z_axis or rotation_vector")


def color(value, path):
    if value is None:
        return None
    if isinstance(value, str) and re.fullmatch(r"#[0-9a-fA-F]{6}", value):
        return tuple(int(value[i:i + 2], 16) / 255 for i in (1, 3, 5))
    if isinstance(value, list) and len(value) == 3 and all(isinstance(c, (int, float)) and 0 <= c <= 1
                                                          for c in value):
        return tuple(float(c) for c in value)
    raise VisualError(f"{path}: expected a colour \"#rrggbb\" or [r, g, b] in 0..1")


def visual_list(owner, path):
    """A body's `visual`: one object or a list of them."""
    v = owner.get("visual")
    if v is None:
        return []
    items = v if isinstance(v, list) else [v]
    for i, item in enumerate(items):
        if not isinstance(item, dict):
            raise VisualError(f"{path}.visual[{i}]: expected an object")
    return [(item, f"{path}.visual" + (f"[{i}]" if isinstance(v, list) else "")) for i, item in enumerate(items)]
