"""The direction of dependencies (docs/design.md 2): each layer of the solver
includes only the layers before it, the FMI layer reaches the solver
through the Simulation, and the controller FMU knows no mechanics. Reads
the project's own #include lines."""
import re

import pytest

from conftest import ROOT

# Layer -> the layers its files may include (itself among them).
BEFORE = {
    "math": [],
    "scene": ["math"],
    "flex": ["math", "scene"],
    "coupling": ["math", "scene"],
    "model": ["math", "scene", "flex", "coupling"],
    "rigid": ["math", "scene", "flex", "coupling", "model"],
    "integrator": ["math"],
    "system": ["math", "scene", "flex", "coupling", "model", "rigid", "integrator"],
    "simulation": ["math", "scene", "flex", "coupling", "model", "rigid", "integrator", "system"],
    "modelDescription": ["math", "scene", "model", "simulation"],
    "fmu_src": ["math", "scene", "simulation", "modelDescription"],
    "controller": ["math", "fmu_src"],
}
# The files directly in solver/: the System and its job files, then the
# Simulation's. A new file there is placed here on purpose.
TOP_LEVEL = {
    "system": ["system", "two_marker_constraints", "constraint_rows", "joint_space_tangent",
               "recursive_newton_matrix"],
    "simulation": ["simulation", "mechanism_assembly", "output_derivatives", "initial_equilibrium",
                   "integrator_choice"],
}
INCLUDE = re.compile(r'^#include "([^"]+)"', re.MULTILINE)


def layer_of(path):
    """The layer of a source file (a path relative to the root), or None."""
    parts = path.parts
    if parts[0] in ("modelDescription", "fmu_src", "controller"):
        return parts[0]
    if parts[0] != "solver":
        return None
    if len(parts) > 2:
        return parts[1]
    for layer, stems in TOP_LEVEL.items():
        if path.stem in stems:
            return layer
    raise AssertionError(f"{path}: a file in solver/ that no layer of TOP_LEVEL names")


def sources():
    for folder in ("solver", "modelDescription", "fmu_src", "controller"):
        for path in sorted((ROOT / folder).rglob("*")):
            if path.suffix in (".hpp", ".cpp", ".h"):
                yield path.relative_to(ROOT)


def included_layer(source, name):
    """The layer of the project file an include names, or None (a library's)."""
    for base in (ROOT / source.parent, ROOT / "solver", ROOT / "modelDescription", ROOT / "fmu_src"):
        if (base / name).is_file():
            return layer_of((base / name).resolve().relative_to(ROOT))
    return None


def test_every_solver_folder_is_a_layer():
    folders = {p.name for p in (ROOT / "solver").iterdir() if p.is_dir()}
    assert folders <= set(BEFORE), folders - set(BEFORE)


@pytest.mark.parametrize("source", list(sources()), ids=str)
def test_includes_run_one_way(source):
    layer = layer_of(source)
    against = []
    for name in INCLUDE.findall((ROOT / source).read_text()):
        target = included_layer(source, name)
        if target is not None and target != layer and target not in BEFORE[layer]:
            against.append(f"{name} ({target})")
    assert not against, f"{source} ({layer}) includes against the direction: {', '.join(against)}"
