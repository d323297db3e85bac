#!/usr/bin/env python3
"""Reads a run's snapshots (pdamp run --snapshots) with VTK's own reader (Debian's python3-vtk9)
and checks them: the .pvd lists every frame of the folder, in order, each with its spheres and its
cavity; every .vtp reads without error, with the arrays, components and types of docs/snapshots.md
and its time; the spheres are inside the cavity drawn at the host's position. With --dump, every
value equals the engine's state that the C++ test dumped at each frame; with --db, the frames agree
with the run's stored samples (host position, and the spheres' energies and dissipation summed) and
the store says where the snapshots are. Exit 0 if all holds, 1 with the failures listed otherwise.

usage: check_snapshots.py COLLECTION.pvd [--dump FILE] [--db STORE --run RUN_ID]
"""
import argparse
import configparser
import math
import os
import sqlite3
import sys
import xml.etree.ElementTree as ET

try:
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
except ImportError as e:
    sys.exit(f"check_snapshots: VTK's Python module is missing ({e}): install Debian's python3-vtk9 "
             "(tools/setup.sh does) and run this with /usr/bin/python3")

SPHERE_ARRAYS = [("radius_m", 1), ("velocity_m_s", 3), ("spin_rad_s", 3), ("dissipated_impact_J", 1),
                 ("dissipated_friction_J", 1), ("id", 1)]
CAVITY_SEGMENTS = 64
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
    return ok


def read_poly_data(path):
    errors = []
    reader = vtk.vtkXMLPolyDataReader()
    reader.AddObserver("ErrorEvent", lambda obj, event: errors.append(event))
    reader.GetExecutive().AddObserver("ErrorEvent", lambda obj, event: errors.append(event))
    reader.SetFileName(path)
    reader.Update()
    data = reader.GetOutput()
    if check(not errors and reader.GetErrorCode() == 0 and data.GetPoints() is not None,
             f"{path}: VTK could not read it ({errors})"):
        return data
    return None


def field(data, name):
    array = data.GetFieldData().GetArray(name)
    return array.GetValue(0) if array is not None else None


def frames_of(collection):
    """[(time, spheres file, cavity file)] in frame order, checking the collection's structure."""
    root = ET.parse(collection).getroot()
    check(root.tag == "VTKFile" and root.get("type") == "Collection", f"{collection}: not a VTK collection")
    by_time = {}
    for data_set in root.iter("DataSet"):
        by_time.setdefault(float(data_set.get("timestep")), {})[data_set.get("part")] = data_set.get("file")
    frames = []
    for k, time in enumerate(sorted(by_time)):
        parts = by_time[time]
        expected = {"0": f"spheres_{k:06d}.vtp", "1": f"cavity_{k:06d}.vtp"}
        check(parts == expected, f"frame {k} at t = {time}: lists {parts}, expected {expected}")
        frames.append((time, parts.get("0"), parts.get("1")))
    folder = os.path.dirname(collection)
    on_disk = sorted(f for f in os.listdir(folder) if f.endswith(".vtp"))
    listed = sorted(f for _, s, c in frames for f in (s, c) if f)
    check(on_disk == listed, f"{folder}: {len(on_disk)} .vtp files, the collection lists {len(listed)}")
    return frames


def check_spheres(path, time):
    data = read_poly_data(path)
    if data is None:
        return {}
    n = data.GetNumberOfPoints()
    point_data = data.GetPointData()
    names = [point_data.GetArrayName(i) for i in range(point_data.GetNumberOfArrays())]
    check(names == [name for name, _ in SPHERE_ARRAYS], f"{path}: point arrays {names}")
    arrays = {}
    for name, components in SPHERE_ARRAYS:
        array = point_data.GetArray(name)
        if not check(array is not None, f"{path}: no array {name}"):
            continue
        check(array.GetNumberOfComponents() == components and array.GetNumberOfTuples() == n,
              f"{path}: {name} has {array.GetNumberOfTuples()} x {array.GetNumberOfComponents()} values")
        arrays[name] = vtk_to_numpy(array)
        expected = "int64" if name == "id" else "float64"
        check(arrays[name].dtype == expected, f"{path}: {name} is {arrays[name].dtype}, not {expected}")
    check(data.GetNumberOfVerts() == n and data.GetNumberOfPolys() == 0, f"{path}: {data.GetNumberOfVerts()} verts")
    check(data.GetPoints().GetDataType() == vtk.VTK_DOUBLE, f"{path}: points not Float64")
    check(field(data, "TimeValue") == time, f"{path}: TimeValue {field(data, 'TimeValue')}, the collection says {time}")
    if "id" in arrays:
        check(list(arrays["id"]) == list(range(n)), f"{path}: ids are not 0 .. {n - 1}")
    arrays["position_m"] = vtk_to_numpy(data.GetPoints().GetData())
    return arrays


def check_cavity(path, time):
    """The cavity's radius, height and bottom (m) as drawn."""
    data = read_poly_data(path)
    if data is None:
        return None
    points = vtk_to_numpy(data.GetPoints().GetData())
    check(len(points) == 2 * CAVITY_SEGMENTS and data.GetNumberOfPolys() == CAVITY_SEGMENTS + 2,
          f"{path}: {len(points)} points, {data.GetNumberOfPolys()} polygons")
    check(field(data, "TimeValue") == time, f"{path}: TimeValue {field(data, 'TimeValue')}, the collection says {time}")
    host_z = field(data, "host_z_m")
    check(host_z is not None and field(data, "host_v_m_s") is not None, f"{path}: no host_z_m or host_v_m_s")
    radii = [math.hypot(x, y) for x, y, _ in points]
    bottom, top = points[:CAVITY_SEGMENTS, 2], points[CAVITY_SEGMENTS:, 2]
    check(all(z == host_z for z in bottom), f"{path}: the bottom rim is not at host_z_m = {host_z}")
    check(max(radii) - min(radii) <= 1e-12 * max(radii), f"{path}: the rim is not a circle")
    return max(radii), top[0] - bottom[0], host_z


def check_inside(path, spheres, cavity):
    radius, height, host_z = cavity
    for (x, y, z), r in zip(spheres["position_m"], spheres["radius_m"]):
        slack = 0.5 * r  # soft contacts overlap the walls a little
        if not check(math.hypot(x, y) + r <= radius + slack and host_z - slack <= z - r and
                     z + r <= host_z + height + slack,
                     f"{path}: a sphere at ({x}, {y}, {z}) m, radius {r} m, is outside the cavity"):
            return


def read_dump(path):
    """{time: [[id, x, y, z, r, vx, vy, vz, wx, wy, wz, impact, friction], ...]} as the test wrote them."""
    frames, rows = {}, None
    with open(path) as f:
        for line in f:
            words = line.split()
            if words[0] == "frame":
                rows = frames.setdefault(float(words[1]), [])
            else:
                rows.append([float(w) for w in words])
    return frames


def compare_with_dump(time, spheres, dump):
    rows = dump.get(time)
    if not check(rows is not None, f"t = {time}: no state dumped"):
        return
    check(len(rows) == len(spheres["radius_m"]), f"t = {time}: {len(spheres['radius_m'])} spheres, dumped {len(rows)}")
    columns = [("id", None), ("position_m", 0), ("position_m", 1), ("position_m", 2), ("radius_m", None),
               ("velocity_m_s", 0), ("velocity_m_s", 1), ("velocity_m_s", 2), ("spin_rad_s", 0), ("spin_rad_s", 1),
               ("spin_rad_s", 2), ("dissipated_impact_J", None), ("dissipated_friction_J", None)]
    for i, row in enumerate(rows):
        for value, (name, c) in zip(row, columns):
            read = spheres[name][i] if c is None else spheres[name][i][c]
            if not check(float(read) == value, f"t = {time}, sphere {i}: {name} {read}, the engine had {value}"):
                return


def scenario_of(db, run_id):
    text = db.execute("SELECT scenario_text FROM runs WHERE run_id = ?", (run_id,)).fetchone()[0]
    scenario = configparser.ConfigParser()
    scenario.read_string(text)
    return scenario


def compare_with_store(collection, frames, spheres_by_time, cavities, db_file, run_id):
    db = sqlite3.connect(f"file:{db_file}?mode=ro", uri=True)
    row = db.execute("SELECT collection, frames FROM run_snapshots WHERE run_id = ?", (run_id,)).fetchone()
    if not check(row is not None, f"run {run_id}: the store records no snapshots"):
        return
    check(os.path.samefile(row[0], collection), f"run {run_id}: the store says the snapshots are in {row[0]}")
    check(row[1] == len(frames), f"run {run_id}: the store says {row[1]} frames, the collection lists {len(frames)}")
    scenario = scenario_of(db, run_id)
    density = float(scenario["particles"]["density_kg_m3"])
    g = [float(w) for w in scenario["gravity"]["g_m_s2"].split("#")[0].split()]
    gravity = [0.0, 0.0, -g[0]] if len(g) == 1 else g
    cavity_radius = 0.5 * float(scenario["cavity"]["diameter_m"])
    diameters = [float(w) for w in scenario["particles"]["diameter_m"].split("#")[0].split()]
    smallest, largest = 0.5 * min(diameters), 0.5 * max(diameters)
    matched = 0
    for time, _, _ in frames:
        sample = db.execute(
            "SELECT host_z_m, particle_translational_J, particle_rotational_J, gravitational_potential_J, "
            "dissipated_impact_J, dissipated_friction_J FROM samples WHERE run_id = ? AND abs(t_s - ?) <= 1e-12",
            (run_id, time)).fetchone()
        if sample is None:
            continue
        matched += 1
        s = spheres_by_time.get(time)
        if not s or not cavities.get(time):
            continue  # unreadable: reported already
        radius, height, host_z = cavities[time]
        check(host_z == sample[0], f"t = {time}: the cavity is at {host_z} m, the stored host at {sample[0]} m")
        check(abs(radius - cavity_radius) <= 1e-12 * cavity_radius,
              f"t = {time}: cavity radius {radius} m, the scenario's {cavity_radius} m")
        check(all(smallest * (1 - 1e-12) <= r <= largest * (1 + 1e-12) for r in s["radius_m"]),
              f"t = {time}: radii outside the scenario's {smallest} .. {largest} m")
        mass = [density * 4.0 / 3.0 * math.pi * r ** 3 for r in s["radius_m"]]
        energies = {
            "particle_translational_J": sum(0.5 * m * (v @ v) for m, v in zip(mass, s["velocity_m_s"])),
            "particle_rotational_J": sum(0.2 * m * r * r * (w @ w) for m, r, w in
                                         zip(mass, s["radius_m"], s["spin_rad_s"])),
            "gravitational_potential_J": -sum(m * sum(g * c for g, c in zip(gravity, x))
                                              for m, x in zip(mass, s["position_m"])),
            "dissipated_impact_J": float(s["dissipated_impact_J"].sum()),
            "dissipated_friction_J": float(s["dissipated_friction_J"].sum()),
        }
        for (name, value), stored in zip(energies.items(), sample[1:]):
            check(abs(value - stored) <= 1e-9 * max(abs(stored), 1e-12),
                  f"t = {time}: {name} from the snapshot {value}, stored {stored}")
    check(matched >= 2, f"run {run_id}: only {matched} frames fall on stored samples")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("collection")
    parser.add_argument("--dump")
    parser.add_argument("--db")
    parser.add_argument("--run", type=int)
    args = parser.parse_args()
    frames = frames_of(args.collection)
    check(len(frames) >= 2, f"{args.collection}: {len(frames)} frames")
    check([t for t, _, _ in frames] == sorted(t for t, _, _ in frames), "the frames' times do not increase")
    folder = os.path.dirname(args.collection)
    dump = read_dump(args.dump) if args.dump else None
    spheres_by_time, cavities = {}, {}
    for time, spheres_file, cavity_file in frames:
        if not (spheres_file and cavity_file):
            continue
        spheres = check_spheres(os.path.join(folder, spheres_file), time)
        cavity = check_cavity(os.path.join(folder, cavity_file), time)
        if "radius_m" in spheres and cavity:
            check_inside(spheres_file, spheres, cavity)
        if dump is not None and len(spheres) > len(SPHERE_ARRAYS):
            compare_with_dump(time, spheres, dump)
        spheres_by_time[time], cavities[time] = spheres, cavity
    if dump is not None:
        check(sorted(dump) == [t for t, _, _ in frames], f"frames at {[t for t, _, _ in frames]}, dumped {sorted(dump)}")
    if args.db:
        compare_with_store(args.collection, frames, spheres_by_time, cavities, args.db, args.run)
    for failure in failures[:50]:
        print("check_snapshots:", failure, file=sys.stderr)
    if failures:
        sys.exit(1)
    print(f"check_snapshots: {len(frames)} frames of {args.collection} read by VTK {vtk.vtkVersion.GetVTKVersion()}: "
          f"all checks hold")


if __name__ == "__main__":
    main()
