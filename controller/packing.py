"""What the controller's two packers share (pack_controller.py: the
controller FMU; make_ssp.py: the SSP files): XML documents as text, and
zip archives of named entries, deflated."""
import pathlib
import xml.etree.ElementTree as ET
import zipfile


def xml_text(root):
    """An ElementTree as an indented UTF-8 document with its declaration."""
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_zip(out, entries):
    """Writes `entries` ({name in the archive: text, bytes, or the path of a
    file to copy}) to the zip file `out`, deflated."""
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries.items():
            if isinstance(data, pathlib.Path):
                z.write(data, name)
            else:
                z.writestr(name, data)
