#!/usr/bin/env python3
"""The run's ParaView outputs read back with VTK's own readers (python3-vtk9): a scene with a
gradient, a Hessian (both with exact values) and a solve with a Neumann boundary group writes
a zlib-compressed .vtu and an uncompressed .vtp. VTK must read both (the .vtp as PolyData),
find the gradient as one 3-component array, the Hessian as one 6-component symmetric tensor,
their _exact and _error arrays, the solve's u_kind and u_normal (3 components) and the row
status, with the values the scene defines (the gradient of x^2 + 3xy is exact for qsfdi).

Usage: vtk_outputs.py PSTENCIL WORKDIR
"""
import os
import subprocess
import sys

try:
    import vtk
except ImportError:
    sys.exit("vtk_outputs: cannot import vtk with %s: install python3-vtk9" % sys.executable)

exe, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAILED: " + what, file=sys.stderr)


SCENE = """{ "dim": 2,
  "cloud": { "source": "lattice", "lo": [0, 0], "hi": [1, 1], "spacing": 0.05,
             "jitter": 0.2, "seed": 3, "boundary_layer": true },
  "fields": { "f": "x^2 + 3*x*y" },
  "tasks": [
    { "type": "gradient", "name": "g", "field": "f", "exact": ["2*x + 3*y", "3*x"] },
    { "type": "hessian", "name": "H", "field": "f", "exact": ["2", "0", "3"] },
    { "type": "solve", "name": "u", "rhs": "4", "exact": "x^2 + y^2",
      "boundary": [ { "where": "xhi", "type": "neumann", "normals": "face", "value": "2*x" },
                    { "type": "dirichlet", "value": "x^2 + y^2" } ] } ],
  "outputs": { "vtu": "%s", "vtu_compress": %s } }
"""


def run(name, compress):
    path = os.path.join(work, name)
    scene = os.path.join(work, name + ".json")
    with open(scene, "w") as f:
        f.write(SCENE % (path, "true" if compress else "false"))
    subprocess.run([exe, "--quiet", "run", scene], check=True)
    return path


def arrays(data):
    pd = data.GetPointData()
    return {pd.GetArrayName(k): pd.GetArray(k) for k in range(pd.GetNumberOfArrays())}


def tuples(arr):
    return [arr.GetTuple(i) for i in range(arr.GetNumberOfTuples())]


def check_data(data, what):
    n = data.GetNumberOfPoints()
    check(n == 441, "%s: 441 points, got %d" % (what, n))
    a = arrays(data)
    for name, comps in [("g", 3), ("g_exact", 3), ("g_error", 3), ("H", 6), ("H_exact", 6),
                        ("H_error", 6), ("u", 1), ("u_kind", 1), ("u_normal", 3),
                        ("status", 1), ("normal", 3)]:
        check(name in a, "%s: array %s" % (what, name))
        if name in a:
            got = a[name].GetNumberOfComponents()
            check(got == comps, "%s: %s has %d components, not %d" % (what, name, got, comps))
    if not all(k in a for k in ("g", "g_exact", "H", "u_kind", "u_normal")):
        return
    pts = [data.GetPoint(i) for i in range(n)]
    g, ge = tuples(a["g"]), tuples(a["g_exact"])
    worst = max(abs(g[i][c] - ge[i][c]) for i in range(n) for c in range(3))
    check(worst < 1e-9, "%s: gradient against exact, worst %.2e" % (what, worst))
    ex = [(2 * pts[i][0] + 3 * pts[i][1], 3 * pts[i][0], 0.0) for i in range(n)]
    worst = max(abs(ge[i][c] - ex[i][c]) for i in range(n) for c in range(3))
    check(worst < 1e-12, "%s: g_exact is the scene's exact gradient, worst %.2e" % (what, worst))
    h = tuples(a["H"])  # XX YY ZZ XY YZ XZ
    worst = max(max(abs(h[i][0] - 2), abs(h[i][1]), abs(h[i][3] - 3), abs(h[i][2]),
                    abs(h[i][4]), abs(h[i][5])) for i in range(n))
    check(worst < 1e-7, "%s: Hessian in ParaView's order, worst %.2e" % (what, worst))
    kind, nrm = [t[0] for t in tuples(a["u_kind"])], tuples(a["u_normal"])
    neumann = [i for i in range(n) if kind[i] == 2]
    check(len(neumann) > 0, "%s: the solve's Neumann particles in u_kind" % what)
    check(all(nrm[i][0] == 1 and nrm[i][1] == 0 for i in neumann),
          "%s: the Neumann particles' normals are the xhi face's" % what)


r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(run("out.vtu", True))
r.Update()
check_data(r.GetOutput(), "compressed .vtu")
with open(os.path.join(work, "out.vtu"), "rb") as f:
    check(b'compressor="vtkZLibDataCompressor"' in f.read(400), ".vtu names its compressor")

p = vtk.vtkXMLPolyDataReader()
p.SetFileName(run("out.vtp", False))
p.Update()
check(p.GetOutput().GetNumberOfVerts() == 441, ".vtp: one vertex per particle")
check_data(p.GetOutput(), ".vtp")

if failures:
    sys.exit("vtk_outputs: %d check(s) failed" % len(failures))
print("vtk_outputs: the compressed .vtu and the .vtp read back with VTK %s"
      % vtk.vtkVersion.GetVTKVersion())
