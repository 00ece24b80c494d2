#!/usr/bin/python3
"""Writes the open3d_* reference files of tests/data with Debian's python3-open3d (0.16).

The values are a closed form of the index so that the C++ tests can recompute them:
point i = (i, 2 i, -0.5 i) mm, normal i = unit (1, i, 0), colour i = (i/9, 0.5, 1 - i/9).
Run from tests/data: /usr/bin/python3 make_open3d_files.py
"""
import numpy as np
import open3d as o3d

n = 10
i = np.arange(n, dtype=np.float64)
points = np.stack([i, 2 * i, -0.5 * i], axis=1)
normals = np.stack([np.ones(n), i, np.zeros(n)], axis=1)
normals /= np.linalg.norm(normals, axis=1, keepdims=True)
colors = np.stack([i / 9, np.full(n, 0.5), 1 - i / 9], axis=1)

cloud = o3d.geometry.PointCloud()
cloud.points = o3d.utility.Vector3dVector(points)
cloud.normals = o3d.utility.Vector3dVector(normals)
cloud.colors = o3d.utility.Vector3dVector(colors)
o3d.io.write_point_cloud("open3d_cloud_binary.ply", cloud, write_ascii=False)
o3d.io.write_point_cloud("open3d_cloud_ascii.ply", cloud, write_ascii=True)

# A unit cube (8 vertices, 12 triangles), scaled to 10 mm.
mesh = o3d.geometry.TriangleMesh.create_box(10.0, 10.0, 10.0)
mesh.compute_triangle_normals()
o3d.io.write_triangle_mesh("open3d_cube_binary.stl", mesh, write_ascii=False)
# Open3D 0.16 cannot write ascii STL: the same triangles in ascii, written here, with a
# multi-word solid name and CRLF line ends as some Windows exporters write them.
v = np.asarray(mesh.vertices)
with open("cube_ascii.stl", "w", newline="\r\n") as f:
    f.write("solid cube from open3d create_box\n")
    for tri, normal in zip(np.asarray(mesh.triangles), np.asarray(mesh.triangle_normals)):
        f.write("  facet normal %g %g %g\n    outer loop\n" % tuple(normal))
        for k in tri:
            f.write("      vertex %g %g %g\n" % tuple(v[k]))
        f.write("    endloop\n  endfacet\n")
    f.write("endsolid cube from open3d create_box\n")
o3d.io.write_triangle_mesh("open3d_cube.ply", mesh, write_ascii=True, write_vertex_normals=False,
                           write_vertex_colors=False)
