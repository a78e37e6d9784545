#!/usr/bin/env python3
"""Round trip of pst_cloud_write_vtu through VTK's own reader (vtkXMLUnstructuredGridReader,
Debian package python3-vtk9): tests/vtu_dump writes 2D and 3D clouds whose values are known
functions of position (see vtu_dump.c); this script reads each file and checks the number of
points and cells, the array names, types and component counts in order, and every value.
It also checks that the file has the same bytes for 1 and 3 OpenMP threads.

Usage: vtu_roundtrip.py VTU_DUMP WORKDIR
"""
import math
import os
import subprocess
import sys

try:
    import vtk
except ImportError:
    sys.exit("vtu_roundtrip: cannot import vtk with %s: install python3-vtk9 "
             "(scripts/install-deps.sh)" % sys.executable)

S0 = 0.125
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAILED: " + what, file=sys.stderr)


def near(a, b, tol=1e-14):
    return abs(a - b) <= tol * max(1.0, abs(b))


def dump(exe, dim, path, threads):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    out = subprocess.run([exe, str(dim), repr(S0), path], env=env, check=True,
                         stdout=subprocess.PIPE, text=True).stdout
    return int(out)


def read(path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    messages = []
    for event in ("ErrorEvent", "WarningEvent"):
        reader.AddObserver(event, lambda obj, ev: messages.append(ev))
    reader.SetFileName(path)
    reader.Update()
    check(not messages, "%s: reader reported %s" % (path, messages))
    check(reader.GetErrorCode() == 0, "%s: reader error code %d" % (path, reader.GetErrorCode()))
    return reader.GetOutput()


def check_cloud(exe, dim, workdir):
    path = os.path.join(workdir, "cloud%dd.vtu" % dim)
    n = dump(exe, dim, path, 1)
    side = round(1 / S0) + 1
    check(n == side ** dim, "%dD: vtu_dump wrote %d particles, expected %d" % (dim, n, side ** dim))

    # the same bytes for another thread count (the Morton sort runs in parallel)
    again = os.path.join(workdir, "cloud%dd_t3.vtu" % dim)
    dump(exe, dim, again, 3)
    with open(path, "rb") as f1, open(again, "rb") as f3:
        check(f1.read() == f3.read(), "%dD: files differ between 1 and 3 threads" % dim)

    grid = read(path)
    tag = "%dD" % dim
    check(grid.GetNumberOfPoints() == n, "%s: %d points, expected %d"
          % (tag, grid.GetNumberOfPoints(), n))
    check(grid.GetNumberOfCells() == n, "%s: %d cells, expected %d"
          % (tag, grid.GetNumberOfCells(), n))
    check(grid.GetPoints().GetDataType() == vtk.VTK_DOUBLE, tag + ": points are not Float64")

    pd = grid.GetPointData()
    mob = "M" if dim == 2 else "m"
    names = [pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays())]
    expect = ["id", "kind", "V", "h", "normal", mob, "status", "u", "rhs"]
    check(names == expect, "%s: arrays %s, expected %s" % (tag, names, expect))
    if names != expect:
        return
    comps = {"normal": 3, "M": 3}
    for name in expect:
        arr = pd.GetArray(name)
        check(arr.GetNumberOfTuples() == n, "%s: %s has %d tuples" % (tag, name, arr.GetNumberOfTuples()))
        check(arr.GetNumberOfComponents() == comps.get(name, 1),
              "%s: %s has %d components" % (tag, name, arr.GetNumberOfComponents()))
        if name == "id":
            ok = arr.GetDataTypeSize() == 8 and arr.GetDataType() in (
                vtk.VTK_LONG, vtk.VTK_LONG_LONG, vtk.VTK_ID_TYPE)
        elif name in ("kind", "status"):
            ok = arr.GetDataType() == vtk.VTK_UNSIGNED_CHAR
        else:
            ok = arr.GetDataType() == vtk.VTK_DOUBLE
        check(ok, "%s: %s has type %s" % (tag, name, arr.GetDataTypeAsString()))

    a = {name: pd.GetArray(name) for name in expect}
    bad = {}

    def expect_value(name, got, want, tol=1e-14):
        if not near(got, want, tol):
            bad.setdefault(name, (k, got, want))

    for k in range(n):
        p = grid.GetPoint(k)
        x, y, z = p
        if dim == 2:
            expect_value("z", z, 0.0, 0.0)
        expect_value("id", a["id"].GetValue(k), k, 0.0)
        boundary = any(near(p[d], 0.0, 1e-12) or near(p[d], 1.0, 1e-12) for d in range(dim))
        expect_value("kind", a["kind"].GetValue(k), 1 if boundary else 0, 0.0)
        expect_value("V", a["V"].GetValue(k), S0 ** dim)
        expect_value("h", a["h"].GetValue(k), 0.1 + 0.05 * x)
        nrm = a["normal"].GetTuple3(k)
        for d in range(3):
            if d < dim:
                expect_value("normal", nrm[d], p[d] - 0.5)
            else:
                expect_value("normal", nrm[d], 0.0, 0.0)
        if dim == 2:
            m = a["M"].GetTuple3(k)
            expect_value("M", m[0], 1 + x)
            expect_value("M", m[1], 2 + y)
            expect_value("M", m[2], 0.0, 0.0)
        else:
            expect_value("m", a["m"].GetValue(k), 1 + x * y * z)
        expect_value("status", a["status"].GetValue(k), k % 5, 0.0)
        expect_value("u", a["u"].GetValue(k),
                     math.sin(3 * x) + y * y + (math.cos(z) if dim == 3 else 0.0))
        expect_value("rhs", a["rhs"].GetValue(k), x - 2 * y)
        cell = grid.GetCell(k)
        if grid.GetCellType(k) != vtk.VTK_VERTEX or cell.GetNumberOfPoints() != 1 \
                or cell.GetPointId(0) != k:
            bad.setdefault("cells", (k, grid.GetCellType(k), cell.GetPointId(0)))
    before = len(failures)
    for name, (k, got, want) in sorted(bad.items()):
        check(False, "%s: %s at point %d: got %r, expected %r" % (tag, name, k, got, want))
    kinds = [a["kind"].GetValue(k) for k in range(n)]
    check(0 < kinds.count(1) < n, "%s: %d Dirichlet particles" % (tag, kinds.count(1)))
    if len(failures) == before:
        print("%s: %d points, arrays %s: ok" % (tag, n, ",".join(names)))


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: vtu_roundtrip.py VTU_DUMP WORKDIR")
    exe, workdir = sys.argv[1], sys.argv[2]
    os.makedirs(workdir, exist_ok=True)
    print("VTK %s (%s)" % (vtk.vtkVersion.GetVTKVersion(), sys.executable))
    for dim in (2, 3):
        check_cloud(exe, dim, workdir)
    if failures:
        sys.exit("vtu_roundtrip: %d failure(s)" % len(failures))
    print("vtu_roundtrip: ok")


if __name__ == "__main__":
    main()
