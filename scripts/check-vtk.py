#!/usr/bin/env python3
"""Reads a run's ParaView series back with VTK's own readers and checks it against the run.

Usage: check-vtk.py RUN_DIR

RUN_DIR is the output directory of `dda3d run --vtk`. For every file listed in vtk/blocks.pvd
and vtk/contacts.pvd (read with VTK's XML readers, independent of dda3d's writer):
- the number of cells equals the number of blocks in blocks.csv at that time;
- every cell is a polyhedron (VTK type 42) whose volume, computed by VTK from its points and
  faces, equals the solver's volume (the `volume` cell data) to 1e-9 relative;
- the number of contact points equals the rows of contacts.csv at that time;
- the .pvd times are times of blocks.csv rows (as written there, digit for digit).
Prints one line per check and exits 1 on the first failure (2 when vtk cannot be imported).
"""
import csv
import sys
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

try:
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import VTK_POLYHEDRON
    from vtkmodules.vtkFiltersVerdict import vtkCellSizeFilter
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader
except ImportError as e:  # the caller decides whether that is a failure
    print(f"check-vtk: cannot import vtk: {e}", file=sys.stderr)
    sys.exit(2)


def fail(message):
    print(f"check-vtk: FAILED: {message}", file=sys.stderr)
    sys.exit(1)


def series(pvd):
    """(time text, file path) of each data set of a .pvd collection."""
    root = ET.parse(pvd).getroot()
    return [(d.get("timestep"), pvd.parent / d.get("file")) for d in root.iter("DataSet")]


def read(reader_class, path):
    reader = reader_class()
    reader.SetFileName(str(path))
    reader.Update()
    if reader.GetErrorCode() != 0:
        fail(f"{path}: VTK could not read it (error code {reader.GetErrorCode()})")
    return reader.GetOutput()


def check_blocks(path, expected_blocks):
    grid = read(vtkXMLUnstructuredGridReader, path)
    n = grid.GetNumberOfCells()
    if n != expected_blocks:
        fail(f"{path}: {n} cells, blocks.csv has {expected_blocks} blocks at that time")
    for k in range(n):
        if grid.GetCellType(k) != VTK_POLYHEDRON:
            fail(f"{path}: cell {k} has type {grid.GetCellType(k)}, not a polyhedron (42)")
    sizes = vtkCellSizeFilter()
    sizes.SetInputData(grid)
    sizes.ComputeVolumeOn()
    sizes.Update()
    measured = vtk_to_numpy(sizes.GetOutput().GetCellData().GetArray("Volume"))
    solver = vtk_to_numpy(grid.GetCellData().GetArray("volume"))
    worst = max(abs(m - v) / v for m, v in zip(measured, solver))
    if worst > 1e-9:
        fail(f"{path}: a polyhedron's volume differs from the solver's by {worst:.2e} relative")
    return worst


def main():
    run = Path(sys.argv[1])
    with open(run / "blocks.csv", newline="") as f:
        block_rows = Counter(r[0] for r in list(csv.reader(f))[1:])
    with open(run / "contacts.csv", newline="") as f:
        contact_rows = Counter(r[0] for r in list(csv.reader(f))[1:])
    blocks = series(run / "vtk" / "blocks.pvd")
    contacts = series(run / "vtk" / "contacts.pvd")
    if not blocks or [t for t, _ in blocks] != [t for t, _ in contacts]:
        fail("blocks.pvd and contacts.pvd do not list the same times")
    worst = 0.0
    for (t, block_file), (_, contact_file) in zip(blocks, contacts):
        if t not in block_rows:
            fail(f"time {t} of blocks.pvd is not a time of blocks.csv")
        worst = max(worst, check_blocks(block_file, block_rows[t]))
        points = read(vtkXMLPolyDataReader, contact_file).GetNumberOfPoints()
        if points != contact_rows.get(t, 0):
            fail(f"{contact_file}: {points} contacts, contacts.csv has {contact_rows.get(t, 0)}")
    print(
        f"check-vtk: {len(blocks)} outputs read back by VTK: cells, volumes (worst "
        f"{worst:.1e} relative), contacts and times agree with the CSV files"
    )


if __name__ == "__main__":
    main()
