"""Write the example custom body: a 0.5 x 0.3 km contact binary as an OBJ mesh (km).

Two spherical lobes (radii 0.15 and 0.13 km, centres 0.22 km apart along x)
joined at a neck. The surface is the union of the lobes seen from a point inside
both, so each direction of a geodesic icosphere gets the farther of its two ray
hits: the mesh is closed and outward-wound by construction. The mesh is then
shifted so that its origin is the constant-density centre of mass (SPEC
section 1: frame T has its origin there), which ``ideas-hpc body`` checks.

    python campaigns/custom-body/make_contact_binary.py            # contact_binary.obj here
    python campaigns/custom-body/make_contact_binary.py --out X.obj --subdivisions 4
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

#: (centre x km, radius km) of the two lobes; the origin lies inside both.
LOBES = ((-0.10, 0.15), (0.12, 0.13))


def contact_binary(subdivisions: int = 3):
    """``(vertices_km, faces)`` of the two-lobe body, origin at its centre of mass."""
    import trimesh

    from ideas_hpc.body.mass_properties import mass_properties

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    u = np.asarray(sphere.vertices)
    u /= np.linalg.norm(u, axis=1)[:, None]
    reach = np.zeros(len(u))
    for cx, r in LOBES:
        uc = u[:, 0] * cx                       # ray from the origin: |t u - c| = r
        reach = np.maximum(reach, uc + np.sqrt(uc * uc - cx * cx + r * r))
    v = u * reach[:, None]
    faces = np.asarray(sphere.faces, dtype=np.int64)
    com = mass_properties(v, faces).com_T_m
    return v - com, faces


def write_obj(path, vertices, faces) -> None:
    with open(path, "w") as fh:
        fh.write("# contact binary, km, origin at the constant-density centre of mass\n")
        fh.writelines(f"v {x:.9f} {y:.9f} {z:.9f}\n" for x, y, z in vertices)
        fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).with_name("contact_binary.obj")))
    ap.add_argument("--subdivisions", type=int, default=3,
                    help="icosphere subdivisions (3: 642 vertices, 1280 faces)")
    args = ap.parse_args(argv)
    v, f = contact_binary(args.subdivisions)
    write_obj(args.out, v, f)
    ext = v.max(axis=0) - v.min(axis=0)
    print(f"wrote {args.out}: {len(v)} vertices, {len(f)} faces, extent "
          f"{ext[0]:.3f} x {ext[1]:.3f} x {ext[2]:.3f} km")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
