#!/usr/bin/env python3
"""Check that dsc-seg's VTK output lines up with the images as VTK reads them.

Usage: python3 .ci/check_frames.py 2d|3d OUTDIR

2d: the area-weighted centroid of the phase-1 triangles of OUTDIR/mesh.vtu
    and the centroid of the phase-1 pixels of OUTDIR/labels.png as
    vtkPNGReader places them agree within one pixel.
3d: the volume-weighted centroid of the phase-1 tetrahedra and the centroid
    of the phase-1 voxels of OUTDIR/labels.tif as vtkTIFFReader places them
    agree within half a voxel.
Both: OUTDIR/scene.vtm opens with vtkXMLMultiBlockDataReader and every data set
in it has points; OUTDIR/scene.pvd (ParaView's collection format, which the
VTK library has no reader for) is well-formed XML, a VTKFile of type
Collection, and lists the same files, each of which opens with VTK's XML
readers and has points. Exits non-zero on failure. Requires the `vtk` package.
"""
import os
import sys
import xml.etree.ElementTree as ET

try:
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOImage import vtkPNGReader, vtkTIFFReader
    from vtkmodules.vtkIOXML import (
        vtkXMLGenericDataObjectReader,
        vtkXMLMultiBlockDataReader,
        vtkXMLUnstructuredGridReader,
    )
except ImportError as e:  # pragma: no cover
    sys.exit(f"check_frames: the Python 'vtk' and 'numpy' packages are required ({e})")


def read(reader, path):
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        sys.exit(f"FAIL {path}: VTK could not read it")
    return reader.GetOutput()


def mesh_centroid(path, phase):
    """Measure-weighted centroid of the cells of `phase` in a .vtu."""
    grid = read(vtkXMLUnstructuredGridReader(), path)
    points = vtk_to_numpy(grid.GetPoints().GetData())
    conn = vtk_to_numpy(grid.GetCells().GetConnectivityArray())
    labels = vtk_to_numpy(grid.GetCellData().GetArray("phase"))
    n = 3 if grid.GetCellType(0) == 5 else 4
    cells = points[conn.reshape(-1, n)][labels == phase]
    edges = cells[:, 1:] - cells[:, :1]
    if n == 3:
        a, b = edges[:, 0], edges[:, 1]
        measure = np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) / 2
    else:
        measure = np.abs(np.linalg.det(edges)) / 6
    return (cells.mean(axis=1) * measure[:, None]).sum(axis=0) / measure.sum()


def image_centroid(reader, path, phase):
    """Centroid of the points (pixel/voxel centres) whose value is `phase`."""
    image = read(reader, path)
    values = vtk_to_numpy(image.GetPointData().GetScalars()).ravel()
    ids = np.flatnonzero(values == phase)
    if ids.size == 0:
        sys.exit(f"FAIL {path}: no pixel of phase {phase}")
    return np.array([image.GetPoint(int(i)) for i in ids]).mean(axis=0), image.GetSpacing()


def check_scene(path):
    reader = vtkXMLMultiBlockDataReader()
    blocks = read(reader, path)
    n = blocks.GetNumberOfBlocks()
    sizes = [blocks.GetBlock(i).GetNumberOfPoints() for i in range(n)]
    if n < 2 or min(sizes) <= 0:
        sys.exit(f"FAIL {path}: {n} data sets with {sizes} points")
    print(f"ok {path}: {n} data sets with {sizes} points")
    return n


def check_collection(path, expected):
    """A .pvd: valid XML listing `expected` files that VTK's readers open."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        sys.exit(f"FAIL {path}: not well-formed XML ({e})")
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        sys.exit(f"FAIL {path}: not a VTKFile of type Collection")
    files = [d.get("file") for d in root.iter("DataSet")]
    if root.find("Collection") is None or len(files) != expected or None in files:
        sys.exit(f"FAIL {path}: {files} (expected {expected} data sets)")
    sizes = []
    for f in files:
        data = read(vtkXMLGenericDataObjectReader(), os.path.join(os.path.dirname(path), f))
        sizes.append(data.GetNumberOfPoints())
    if min(sizes) <= 0:
        sys.exit(f"FAIL {path}: {files} with {sizes} points")
    print(f"ok {path}: {files} open with VTK's readers, {sizes} points")


def main(argv):
    if len(argv) != 3 or argv[1] not in ("2d", "3d"):
        sys.exit(__doc__)
    kind, out = argv[1], argv[2]
    if kind == "2d":
        image, reader, tolerance = f"{out}/labels.png", vtkPNGReader(), 1.0
    else:
        image, reader, tolerance = f"{out}/labels.tif", vtkTIFFReader(), 0.5
    mesh = mesh_centroid(f"{out}/mesh.vtu", 1)
    pixels, spacing = image_centroid(reader, image, 1)
    off = np.abs(mesh - pixels) / np.array(spacing)
    line = f"{kind}: mesh phase-1 centroid {mesh.round(3)}, {image} {pixels.round(3)}, " \
           f"off by {off.round(3)} pixels/voxels"
    if off.max() > tolerance:
        sys.exit(f"FAIL {line} (more than {tolerance})")
    print(f"ok {line}")
    blocks = check_scene(f"{out}/scene.vtm")
    check_collection(f"{out}/scene.pvd", blocks)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
