#!/usr/bin/env python3
"""Round trip of pst_cloud_write_vtu through VTK's own reader (vtkXMLUnstructuredGridReader,
Debian package python3-vtk9): tests/vtu_dump writes 2D and 3D clouds whose values are known
functions of position (see vtu_dump.c); this script reads each file and checks the number of
points and cells, the array names, types and component counts in order, and every value.
It also checks that the file has the same bytes for 1 and 3 OpenMP threads.
The other direction: VTK's vtkXMLUnstructuredGridWriter writes 2D and 3D clouds (V, h as
Float32, kind, a permuted id, normal, a field u, a vector w and a symmetric tensor S) in
appended raw and base64, inline binary (base64) and ascii, with UInt32 and UInt64 headers,
uncompressed and zlib-compressed (SetCompressorTypeToZLib, with blocks small enough that the
arrays span several); `vtu_dump --read` reads each with pst_cloud_read_vtu and prints the
cloud, which must match (exactly, except ascii).

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


# ---- the other direction: VTK writes, pst_cloud_read_vtu reads (vtu_dump --read) ----------

def vtk_cloud(dim):
    """A small cloud as a vtkUnstructuredGrid (one VTK_VERTEX per point) with V (Float64),
    h (Float32), kind (UInt8), id (a permutation, vtkIdType), normal, a field u, a vector w
    (Float32) and a symmetric tensor S (XX, YY, ZZ, XY, YZ, XZ; out of the plane 0 in 2D);
    returns the grid and the expected rows of vtu_dump --read (particle id[k] = file row k)."""
    side = 5
    n = side ** dim
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    arrays = {}
    for name, cls, comps in (("V", vtk.vtkDoubleArray, 1), ("h", vtk.vtkFloatArray, 1),
                             ("kind", vtk.vtkUnsignedCharArray, 1), ("id", vtk.vtkIdTypeArray, 1),
                             ("normal", vtk.vtkDoubleArray, 3), ("u", vtk.vtkDoubleArray, 1),
                             ("w", vtk.vtkFloatArray, 3), ("S", vtk.vtkDoubleArray, 6)):
        a = cls()
        a.SetName(name)
        a.SetNumberOfComponents(comps)
        arrays[name] = a
    expect = [None] * n
    for k in range(n):
        idx = [(k // side ** d) % side for d in range(dim)]
        p = [0.25 * i + 0.01 * math.sin(k + d) for d, i in enumerate(idx)]
        if dim == 2:
            p.append(0.0)
        pts.InsertNextPoint(p)
        pid = (7 * k + 3) % n          # n is not a multiple of 7
        V = 1.0 / (k + 3)
        h = 0.5 + k / 64.0             # exact in Float32
        kind = k % 3
        nrm = [math.cos(k), math.sin(k), 0.0 if dim == 2 else 0.5]
        u = math.exp(-k / 7.0)
        w = [k / 8.0, -k / 16.0, 0.0 if dim == 2 else 1 + k / 4.0]  # exact in Float32
        S = [math.sin(k + j) if dim == 3 or j in (0, 1, 3) else 0.0 for j in range(6)]
        arrays["V"].InsertNextValue(V)
        arrays["h"].InsertNextValue(h)
        arrays["kind"].InsertNextValue(kind)
        arrays["id"].InsertNextValue(pid)
        arrays["normal"].InsertNextTuple3(*nrm)
        arrays["u"].InsertNextValue(u)
        arrays["w"].InsertNextTuple3(*w)
        arrays["S"].InsertNextTuple(S)
        keep = range(6) if dim == 3 else (0, 1, 3)
        expect[pid] = p[:dim] + [V, h, kind] + nrm[:dim] + [u] + w[:dim] + [S[j] for j in keep]
    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(pts)
    grid.Allocate(n)
    for k in range(n):
        ids = vtk.vtkIdList()
        ids.InsertNextId(k)
        grid.InsertNextCell(vtk.VTK_VERTEX, ids)
    for name in ("V", "h", "kind", "id", "normal", "u", "w", "S"):
        grid.GetPointData().AddArray(arrays[name])
    return grid, expect


def check_read(exe, dim, workdir):
    grid, expect = vtk_cloud(dim)
    modes = (("appended-raw", "raw", 8), ("appended-raw-uint32", "raw", 4),
             ("appended-base64", "b64", 4), ("binary", "binary", 4), ("binary-uint64", "binary", 8),
             ("ascii", "ascii", 4))
    modes += tuple(("zlib-" + tag, mode, header) for tag, mode, header in modes[:-1])
    for tag, mode, header in modes:
        path = os.path.join(workdir, "vtk%dd_%s.vtu" % (dim, tag))
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(path)
        w.SetInputData(grid)
        if tag.startswith("zlib-"):
            w.SetCompressorTypeToZLib()
            w.SetBlockSize(256)  # several blocks per array, the last one short
        else:
            w.SetCompressorTypeToNone()
        w.SetHeaderTypeToUInt64() if header == 8 else w.SetHeaderTypeToUInt32()
        if mode in ("raw", "b64"):
            w.SetDataModeToAppended()
            w.SetEncodeAppendedData(mode == "b64")
        elif mode == "binary":
            w.SetDataModeToBinary()
        else:
            w.SetDataModeToAscii()
        check(w.Write() == 1, "%dD %s: VTK could not write %s" % (dim, tag, path))
        what = "%dD %s" % (dim, tag)
        res = subprocess.run([exe, "--read", path], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        check(res.returncode == 0, "%s: vtu_dump --read failed: %s" % (what, res.stderr.strip()))
        if res.returncode != 0:
            continue
        lines = res.stdout.splitlines()
        n, got_dim = (int(v) for v in lines[0].split(","))
        check(n == len(expect) and got_dim == dim, "%s: read n=%d dim=%d, expected n=%d dim=%d"
              % (what, n, got_dim, len(expect), dim))
        axes = "xyz"[:dim]
        tensor = ("xx", "yy", "zz", "xy", "yz", "xz") if dim == 3 else ("xx", "yy", "xy")
        header_want = ",".join(list(axes) + ["V", "h", "kind"] + ["n" + a for a in axes] + ["u"]
                               + ["w_" + a for a in axes] + ["S_" + c for c in tensor])
        check(lines[1] == header_want, "%s: columns %s, expected %s" % (what, lines[1], header_want))
        # ascii goes through VTK's decimal printing: near; binary modes: exact
        tol = 1e-6 if mode == "ascii" else 0.0
        bad = None
        for i, line in enumerate(lines[2:]):
            got = [float(v) for v in line.split(",")]
            want = expect[i] if i < len(expect) else []
            if len(got) != len(want) or any(abs(g - e) > tol * max(1.0, abs(e))
                                             for g, e in zip(got, want)):
                bad = (i, got, want)
                break
        check(bad is None and len(lines) == 2 + len(expect),
              "%s: particle %s: got %s, expected %s" % ((what,) + (bad or ("count", "", ""))))
        if bad is None:
            print("%s: VTK wrote, pst_cloud_read_vtu read %d particles: ok" % (what, n))


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: vtu_roundtrip.py VTU_DUMP WORKDIR")
    exe, workdir = sys.argv[1], sys.argv[2]
    os.makedirs(workdir, exist_ok=True)
    print("VTK %s (%s)" % (vtk.vtkVersion.GetVTKVersion(), sys.executable))
    for dim in (2, 3):
        check_cloud(exe, dim, workdir)
    for dim in (2, 3):
        check_read(exe, dim, workdir)
    if failures:
        sys.exit("vtu_roundtrip: %d failure(s)" % len(failures))
    print("vtu_roundtrip: ok")


if __name__ == "__main__":
    main()
