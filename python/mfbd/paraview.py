"""ParaView output: one .vtu per output time (meshio) and a .pvd that lists
them with their times."""
import pathlib
import xml.etree.ElementTree as ET

import meshio


def frame_mesh(drawing, k):
    points, triangles, point_data, cell_data = drawing.frame(k)
    return meshio.Mesh(points, [("triangle", triangles)], point_data=point_data,
                       cell_data={key: [value] for key, value in cell_data.items()})


def write_series(drawing, folder, every=1, name=None):
    """Writes folder/NAME_#####.vtu and folder/NAME.pvd; returns the .pvd path."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    name = name or drawing.result.model
    collection = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    datasets = ET.SubElement(collection, "Collection")
    times = drawing.result.time
    for k in range(0, len(times), every):
        file = f"{name}_{k:05d}.vtu"
        meshio.write(folder / file, frame_mesh(drawing, k), file_format="vtu")
        ET.SubElement(datasets, "DataSet", timestep=repr(float(times[k])), group="", part="0", file=file)
    ET.indent(collection)
    pvd = folder / f"{name}.pvd"
    ET.ElementTree(collection).write(pvd, xml_declaration=True, encoding="utf-8")
    return pvd


def read_series(pvd):
    """[(time, meshio.Mesh)] of a .pvd written by write_series."""
    pvd = pathlib.Path(pvd)
    root = ET.parse(pvd).getroot()
    return [(float(d.get("timestep")), meshio.read(pvd.parent / d.get("file"))) for d in root.iter("DataSet")]
