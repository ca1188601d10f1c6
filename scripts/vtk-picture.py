#!/usr/bin/env python3
"""Renders one output of a run's ParaView series with VTK, off screen, into a PNG.

Usage: vtk-picture.py RUN_DIR OUT.png [--time T] [--azimuth DEG] [--elevation DEG]

Reads vtk/blocks.pvd and vtk/contacts.pvd of RUN_DIR (written by `dda3d run --vtk`), takes the
output closest to T (default: the last), and draws the blocks coloured by the length of their
displacement since t = 0 (fixed blocks grey) with their edges, and every closed contact as a
sphere scaled by its normal force. It is what ParaView shows with a "displacement" colouring
and a Glyph filter on the contacts; it needs the `vtk` package (pip install vtk) and an OpenGL
that works off screen (Mesa's EGL or OSMesa, or a display such as Xvfb).
"""
import argparse
import xml.etree.ElementTree as ET
from pathlib import Path

from vtkmodules.vtkCommonCore import vtkLookupTable
from vtkmodules.vtkFiltersCore import vtkGlyph3D, vtkThreshold
from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader
from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
from vtkmodules.vtkRenderingCore import (
    vtkActor,
    vtkPolyDataMapper,
    vtkRenderer,
    vtkRenderWindow,
    vtkTextActor,
    vtkWindowToImageFilter,
)
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the OpenGL back end)
import vtkmodules.vtkRenderingFreeType  # noqa: F401  (text)
from vtkmodules.vtkCommonDataModel import vtkDataObject


def series(pvd):
    root = ET.parse(pvd).getroot()
    return [(float(d.get("timestep")), pvd.parent / d.get("file")) for d in root.iter("DataSet")]


def read(reader_class, path):
    r = reader_class()
    r.SetFileName(str(path))
    r.Update()
    return r.GetOutput()


def blocks_actor(grid, fixed_value, lut):
    """The blocks with `fixed` equal to `fixed_value`, as a surface with edges."""
    t = vtkThreshold()
    t.SetInputData(grid)
    t.SetInputArrayToProcess(0, 0, 0, vtkDataObject.FIELD_ASSOCIATION_CELLS, "fixed")
    t.SetLowerThreshold(fixed_value)
    t.SetUpperThreshold(fixed_value)
    surface = vtkGeometryFilter()
    surface.SetInputConnection(t.GetOutputPort())
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(surface.GetOutputPort())
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().EdgeVisibilityOn()
    actor.GetProperty().SetAmbient(0.35)
    actor.GetProperty().SetDiffuse(0.7)
    actor.GetProperty().SetEdgeColor(0.15, 0.15, 0.15)
    if fixed_value:
        mapper.ScalarVisibilityOff()
        actor.GetProperty().SetColor(0.72, 0.70, 0.66)
    else:
        mapper.SetScalarModeToUseCellFieldData()
        mapper.SelectColorArray("displacement")
        mapper.SetArrayAccessMode(1)
        mapper.SetLookupTable(lut)
        mapper.SetScalarRange(lut.GetRange())
        mapper.ScalarVisibilityOn()
    return actor


def contacts_actor(contacts, size):
    sphere = vtkSphereSource()
    sphere.SetRadius(1.0)
    glyphs = vtkGlyph3D()
    glyphs.SetInputData(contacts)
    glyphs.SetSourceConnection(sphere.GetOutputPort())
    glyphs.SetInputArrayToProcess(0, 0, 0, 0, "normal_force_magnitude")
    glyphs.SetScaleModeToScaleByScalar()
    # Sphere radius from 0 (no force) to `size` (the largest force of this output).
    rng = contacts.GetPointData().GetArray("normal_force_magnitude").GetRange()
    glyphs.ClampingOn()
    glyphs.SetRange(0.0, max(rng[1], 1e-30))
    glyphs.SetScaleFactor(size)
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(glyphs.GetOutputPort())
    mapper.ScalarVisibilityOff()
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(0.85, 0.1, 0.1)
    return actor


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("out")
    ap.add_argument("--time", type=float)
    ap.add_argument("--azimuth", type=float, default=-60.0)
    ap.add_argument("--elevation", type=float, default=20.0)
    a = ap.parse_args()
    run = Path(a.run)
    blocks = series(run / "vtk" / "blocks.pvd")
    contacts = series(run / "vtk" / "contacts.pvd")
    k = len(blocks) - 1 if a.time is None else min(
        range(len(blocks)), key=lambda i: abs(blocks[i][0] - a.time)
    )
    t = blocks[k][0]
    grid = read(vtkXMLUnstructuredGridReader, blocks[k][1])
    points = read(vtkXMLPolyDataReader, contacts[k][1])

    disp = grid.GetCellData().GetArray("displacement")
    top = max(disp.GetMaxNorm(), 1e-3)
    lut = vtkLookupTable()
    lut.SetVectorModeToMagnitude()
    lut.SetHueRange(0.62, 0.0)
    lut.SetRange(0.0, top)
    lut.Build()

    ren = vtkRenderer()
    ren.SetBackground(0.96, 0.96, 0.94)
    ren.AddActor(blocks_actor(grid, 1, lut))
    ren.AddActor(blocks_actor(grid, 0, lut))
    bounds = grid.GetBounds()
    span = max(bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4])
    if points.GetNumberOfPoints():
        ren.AddActor(contacts_actor(points, 0.012 * span))
    bar = vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle("displacement (m)")
    bar.SetNumberOfLabels(5)
    bar.SetWidth(0.08)
    bar.SetHeight(0.5)
    bar.GetTitleTextProperty().SetColor(0.1, 0.1, 0.1)
    bar.GetLabelTextProperty().SetColor(0.1, 0.1, 0.1)
    ren.AddViewProp(bar)
    caption = vtkTextActor()
    caption.SetInput(f"t = {t:.2f} s   (VTK off screen, from {run.name}/vtk)")
    caption.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    caption.GetTextProperty().SetFontSize(18)
    caption.SetDisplayPosition(12, 12)
    ren.AddViewProp(caption)
    cam = ren.GetActiveCamera()
    cam.SetViewUp(0, 0, 1)
    cam.SetPosition(0, -1, 0)
    cam.SetFocalPoint(0, 0, 0)
    cam.Azimuth(a.azimuth)
    cam.Elevation(a.elevation)
    ren.ResetCamera()
    cam.Zoom(1.3)

    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(1280, 800)
    win.AddRenderer(ren)
    win.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.Update()
    png = vtkPNGWriter()
    png.SetFileName(a.out)
    png.SetInputConnection(grab.GetOutputPort())
    png.Write()
    print(f"wrote {a.out} (t = {t} s)")


if __name__ == "__main__":
    main()
