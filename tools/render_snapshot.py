#!/usr/bin/env python3
"""Renders one frame of a run's snapshots (pdamp run --snapshots) to a PNG without a screen: the
spheres at their size, coloured by the energy each has dissipated so far (impact + friction), in
the cavity drawn as a translucent cylinder. Uses Debian's python3-vtk9, whose OpenGL needs an X
server: on a machine without one run it under xvfb-run (Debian's xvfb):

  xvfb-run -a /usr/bin/python3 tools/render_snapshot.py DIR/run-1/run-1.pvd --time 0.3 --out bed.png
"""
import argparse
import os
import sys
import xml.etree.ElementTree as ET

import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

# Viridis at eight points: perceptually even, and readable in grey.
VIRIDIS = [(0.267, 0.005, 0.329), (0.275, 0.194, 0.496), (0.213, 0.359, 0.552), (0.153, 0.498, 0.558),
           (0.122, 0.633, 0.531), (0.288, 0.762, 0.428), (0.627, 0.854, 0.224), (0.993, 0.906, 0.144)]


def frame_files(collection, time):
    """The spheres' and the cavity's files of the frame nearest `time`, and its time."""
    by_time = {}
    for data_set in ET.parse(collection).getroot().iter("DataSet"):
        by_time.setdefault(float(data_set.get("timestep")), {})[data_set.get("part")] = data_set.get("file")
    nearest = min(by_time, key=lambda t: abs(t - time))
    folder = os.path.dirname(collection)
    return os.path.join(folder, by_time[nearest]["0"]), os.path.join(folder, by_time[nearest]["1"]), nearest


def read(path):
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def spheres_actor(spheres, scale_mJ):
    """The spheres glyphed at their size and coloured by loss from the least to the most
    (or 0 to `scale_mJ`); the colour table and the losses (mJ)."""
    lost = (vtk_to_numpy(spheres.GetPointData().GetArray("dissipated_impact_J")) +
            vtk_to_numpy(spheres.GetPointData().GetArray("dissipated_friction_J"))) * 1e3
    colour = numpy_to_vtk(lost, deep=True)
    colour.SetName("dissipated_mJ")
    spheres.GetPointData().AddArray(colour)
    diameter = numpy_to_vtk(2.0 * vtk_to_numpy(spheres.GetPointData().GetArray("radius_m")), deep=True)
    diameter.SetName("diameter_m")
    spheres.GetPointData().AddArray(diameter)
    ball = vtk.vtkSphereSource()  # of diameter 1, scaled to each sphere's
    ball.SetRadius(0.5)
    ball.SetThetaResolution(16)
    ball.SetPhiResolution(12)
    mapper = vtk.vtkGlyph3DMapper()
    mapper.SetInputData(spheres)
    mapper.SetSourceConnection(ball.GetOutputPort())
    mapper.SetScaleArray("diameter_m")
    mapper.SetScaleModeToScaleByMagnitude()
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray("dissipated_mJ")
    table = vtk.vtkColorTransferFunction()
    low, top = (0.0, scale_mJ) if scale_mJ else (float(lost.min()), float(lost.max()))
    for k, rgb in enumerate(VIRIDIS):
        table.AddRGBPoint(low + (top - low) * k / (len(VIRIDIS) - 1), *rgb)
    mapper.SetLookupTable(table)
    mapper.SetScalarRange(low, top)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    return actor, table, lost


def cavity_actors(cavity):
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(cavity)
    mapper.ScalarVisibilityOff()
    wall = vtk.vtkActor()
    wall.SetMapper(mapper)
    wall.GetProperty().SetColor(0.75, 0.78, 0.82)
    wall.GetProperty().SetOpacity(0.12)
    rims = vtk.vtkFeatureEdges()  # the rims and the wall's outline
    rims.SetInputData(cavity)
    rims.BoundaryEdgesOff()
    rims.ManifoldEdgesOff()
    rims.NonManifoldEdgesOff()
    rims.FeatureEdgesOn()
    rims.SetFeatureAngle(60)
    rims_mapper = vtk.vtkPolyDataMapper()
    rims_mapper.SetInputConnection(rims.GetOutputPort())
    rims_mapper.ScalarVisibilityOff()
    outline = vtk.vtkActor()
    outline.SetMapper(rims_mapper)
    outline.GetProperty().SetColor(0.35, 0.38, 0.42)
    outline.GetProperty().SetLineWidth(1.5)
    return [wall, outline]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("collection", help="the run's .pvd")
    parser.add_argument("--time", type=float, required=True, help="simulated time (s): the nearest frame is drawn")
    parser.add_argument("--out", required=True, help="PNG file")
    parser.add_argument("--size", default="900x560", help="width x height in pixels")
    parser.add_argument("--scale-mJ", type=float,
                        help="colours from 0 to this (default: from the least to the most a sphere lost)")
    parser.add_argument("--title", default="", help="a line of text over the picture")
    parser.add_argument("--elevation", type=float, default=25.0, help="the view's angle above the horizontal (deg)")
    parser.add_argument("--zoom", type=float, default=1.25, help="the view's zoom, 1 to see the whole cavity")
    args = parser.parse_args()
    spheres_file, cavity_file, time = frame_files(args.collection, args.time)
    spheres, cavity = read(spheres_file), read(cavity_file)

    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    balls, table, lost = spheres_actor(spheres, args.scale_mJ)
    renderer.AddActor(balls)
    for actor in cavity_actors(cavity):
        renderer.AddActor(actor)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(table)
    bar.SetTitle("dissipated\nper sphere\n(mJ)")
    bar.SetNumberOfLabels(5)
    bar.SetLabelFormat("%.2g")
    bar.SetOrientationToVertical()
    bar.SetPosition(0.85, 0.1)
    bar.SetWidth(0.12)
    bar.SetHeight(0.8)
    bar.UnconstrainedFontSizeOn()
    for text in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        text.SetColor(0.1, 0.1, 0.1)
        text.ShadowOff()
        text.ItalicOff()
        text.BoldOff()
        text.SetFontSize(14)
    renderer.AddActor2D(bar)
    caption = vtk.vtkTextActor()
    host_z = cavity.GetFieldData().GetArray("host_z_m").GetValue(0)
    caption.SetInput((args.title + "\n" if args.title else "") +
                     f"t = {time:.3f} s, host at {host_z * 1e3:+.2f} mm, {spheres.GetNumberOfPoints()} spheres, "
                     f"{lost.sum():.3g} mJ dissipated in them")
    caption.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    caption.GetTextProperty().SetFontSize(15)
    caption.SetPosition(12, 12)
    renderer.AddActor2D(caption)

    # A side view from `elevation` degrees above, the cavity filling the frame.
    camera = renderer.GetActiveCamera()
    camera.SetFocalPoint(0, 0, 0)
    camera.SetPosition(0, -1, 0)
    camera.SetViewUp(0, 0, 1)
    camera.SetViewAngle(20)
    renderer.ResetCamera(cavity.GetBounds())
    camera.Elevation(args.elevation)
    camera.OrthogonalizeViewUp()
    camera.Zoom(args.zoom)
    renderer.ResetCameraClippingRange()
    light = vtk.vtkLightKit()
    light.AddLightsToRenderer(renderer)

    width, height = (int(v) for v in args.size.split("x"))
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(8)
    window.AddRenderer(renderer)
    window.SetSize(width, height)
    window.Render()
    image = vtk.vtkWindowToImageFilter()
    image.SetInput(window)
    image.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(args.out)
    writer.SetInputConnection(image.GetOutputPort())
    writer.Write()
    print(f"render_snapshot: {args.out}: frame at t = {time} s of {args.collection}", file=sys.stderr)


if __name__ == "__main__":
    main()
