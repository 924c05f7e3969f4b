# Opens an XDMF file with every XDMF reader of ParaView (legacy Xdmf, Xdmf3 S and T, and the one
# OpenDataFile picks) and checks, at each time step, the points, the vertex and line cells and
# the field data against the expectations the test wrote. Run by pvpython; exit code 77 when
# ParaView's Python modules are unusable (the test then skips).
import json
import os
import sys

try:
    from paraview import servermanager
    import paraview.simple as pv
except Exception as error:  # noqa: BLE001 - any import problem means "no usable ParaView"
    print(f"paraview.simple unusable: {error}")
    sys.exit(77)

VTK_VERTEX, VTK_POLY_VERTEX, VTK_LINE, VTK_POLY_LINE = 1, 2, 3, 4


def leaves(data):
    if data is None:
        return []
    if not data.IsA("vtkCompositeDataSet"):
        return [data]
    found = []
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        found.append(it.GetCurrentDataObject())
        it.GoToNextItem()
    return found


def summary(data):
    out = {"points_of_point_grid": 0, "vertex_cells": 0, "line_cells": 0, "field": {},
           "point_arrays": set()}
    for leaf in leaves(data):
        cells = [leaf.GetCellType(i) for i in range(leaf.GetNumberOfCells())]
        vertices = sum(1 for c in cells if c == VTK_VERTEX) + sum(
            leaf.GetCell(i).GetNumberOfPoints() for i, c in enumerate(cells)
            if c == VTK_POLY_VERTEX)
        lines = sum(1 for c in cells if c in (VTK_LINE, VTK_POLY_LINE))
        out["vertex_cells"] += vertices
        out["line_cells"] += lines
        if vertices > 0:
            out["points_of_point_grid"] = leaf.GetNumberOfPoints()
        field = leaf.GetFieldData()
        for i in range(field.GetNumberOfArrays()):
            array = field.GetArray(i)
            if array is not None and array.GetNumberOfTuples() > 0:
                out["field"][array.GetName()] = array.GetTuple1(0)
        for i in range(leaf.GetPointData().GetNumberOfArrays()):
            out["point_arrays"].add(leaf.GetPointData().GetArrayName(i))
    return out


def check(reader_name, reader, expected, problems):
    times = list(reader.TimestepValues) if reader.TimestepValues else []
    wanted = [step["time"] for step in expected["steps"]]
    if len(times) != len(wanted) or any(abs(a - b) > 1e-12 for a, b in zip(times, wanted)):
        problems.append(f"{reader_name}: time steps {times}, expected {wanted}")
        return
    for step in expected["steps"]:
        reader.UpdatePipeline(step["time"])
        got = summary(servermanager.Fetch(reader))
        where = f"{reader_name} at t = {step['time']}"
        print(f"{where}: {got['vertex_cells']} vertex cells, {got['line_cells']} line cells, "
              f"field {sorted(got['field'])}")
        if got["vertex_cells"] != step["points"]:
            problems.append(f"{where}: {got['vertex_cells']} vertex cells for {step['points']} "
                            "points")
        if got["points_of_point_grid"] != step["points"]:
            problems.append(f"{where}: point grid has {got['points_of_point_grid']} points")
        if got["line_cells"] != step["segments"]:
            problems.append(f"{where}: {got['line_cells']} line cells for {step['segments']} "
                            "segments")
        for name in expected["point_arrays"]:
            if name not in got["point_arrays"]:
                problems.append(f"{where}: no point array '{name}'")
        for name, value in step["field"].items():
            if name not in got["field"] or abs(got["field"][name] - value) > 1e-9 * max(
                    1.0, abs(value)):
                problems.append(f"{where}: field '{name}' = {got['field'].get(name)}, "
                                f"expected {value}")


def main():
    xmf, expectations = os.path.abspath(sys.argv[1]), sys.argv[2]
    with open(expectations) as f:
        expected = json.load(f)
    problems = []
    readers = {
        "XDMFReader (legacy Xdmf)": lambda: pv.XDMFReader(FileNames=[xmf]),
        "Xdmf3ReaderS": lambda: pv.Xdmf3ReaderS(FileName=[xmf]),
        "Xdmf3ReaderT": lambda: pv.Xdmf3ReaderT(FileName=[xmf]),
        "OpenDataFile": lambda: pv.OpenDataFile(xmf),
    }
    for name, make in readers.items():
        try:
            reader = make()
        except Exception as error:  # noqa: BLE001
            problems.append(f"{name}: cannot open: {error}")
            continue
        if name == "OpenDataFile":
            name += f" ({reader.GetXMLName()})"
        check(name, reader, expected, problems)
        pv.Delete(reader)
    for problem in problems:
        print("PROBLEM:", problem)
    sys.exit(1 if problems else 0)


main()
