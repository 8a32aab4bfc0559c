#!/usr/bin/env python3
"""Check that VTK's own XML readers open dsc-seg output files.

Usage: python3 .ci/check_vtk.py FILE.vtu|FILE.vtp ...

For each file, reads it with vtkXMLUnstructuredGridReader (.vtu) or
vtkXMLPolyDataReader (.vtp), and asserts that it has points, cells and a
`phase` cell-data array with one value per cell. Exits non-zero on failure.
Requires the `vtk` Python package (`pip install vtk`).
"""
import sys

try:
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader
    from vtkmodules.vtkCommonCore import vtkCommand
except ImportError as e:  # pragma: no cover
    sys.exit(f"check_vtk: the Python 'vtk' package is required ({e})")


class ErrorCatcher:
    """Records VTK error events (VTK readers report errors instead of raising)."""

    def __init__(self):
        self.errors = []

    def __call__(self, obj, event, *args):
        self.errors.append(event)


def check(path):
    if path.endswith(".vtu"):
        reader = vtkXMLUnstructuredGridReader()
    elif path.endswith(".vtp"):
        reader = vtkXMLPolyDataReader()
    else:
        return f"{path}: unknown extension (expected .vtu or .vtp)"
    if not reader.CanReadFile(path):
        return f"{path}: VTK reader cannot read this file"
    catcher = ErrorCatcher()
    reader.AddObserver(vtkCommand.ErrorEvent, catcher)
    reader.SetFileName(path)
    reader.Update()
    if catcher.errors or reader.GetErrorCode() != 0:
        return f"{path}: VTK reported errors while reading"
    data = reader.GetOutput()
    n_points, n_cells = data.GetNumberOfPoints(), data.GetNumberOfCells()
    if n_points <= 0 or n_cells <= 0:
        return f"{path}: {n_points} points, {n_cells} cells (expected > 0)"
    phase = data.GetCellData().GetArray("phase")
    if phase is None:
        return f"{path}: no 'phase' cell array"
    if phase.GetNumberOfTuples() != n_cells:
        return f"{path}: 'phase' has {phase.GetNumberOfTuples()} values for {n_cells} cells"
    names = [data.GetCellData().GetArrayName(i) for i in range(data.GetCellData().GetNumberOfArrays())]
    print(f"ok {path}: {n_points} points, {n_cells} cells, cell arrays {names}, "
          f"phase range {phase.GetRange()}")
    return None


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    failures = [msg for msg in (check(p) for p in argv[1:]) if msg]
    for msg in failures:
        print(f"FAIL {msg}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
