#include <mbi/error.hpp>
#include <mbi/generate/subdivide.hpp>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <string>
#include <vector>

namespace mbi::generate {

// Loop subdivision with OpenMesh (smooth densification of a triangle surface).
void loop_subdivide(io::SurfaceMesh& m, int steps) {
  using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
  Mesh mesh;
  std::vector<Mesh::VertexHandle> vh;
  vh.reserve(static_cast<size_t>(m.V.rows()));
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    vh.push_back(mesh.add_vertex(Mesh::Point(static_cast<float>(m.V(i, 0)),
                                             static_cast<float>(m.V(i, 1)),
                                             static_cast<float>(m.V(i, 2)))));
  int skipped = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const auto fh = mesh.add_face(vh[static_cast<size_t>(m.F(f, 0))], vh[static_cast<size_t>(m.F(f, 1))],
                                  vh[static_cast<size_t>(m.F(f, 2))]);
    if (!fh.is_valid()) ++skipped;
  }
  if (skipped)
    throw mbi::Error("dense.subdivide: the mesh has " + std::to_string(skipped) +
                     " non-manifold faces; Loop subdivision needs a manifold surface");
  // OpenMesh's Loop step leaves a vertex no face uses uninitialised (it averages no
  // neighbours): such vertices keep their position, exactly.
  std::vector<Eigen::Index> unused;
  for (const auto v : mesh.vertices())
    if (mesh.is_isolated(v)) unused.push_back(v.idx());
  OpenMesh::Subdivider::Uniform::LoopT<Mesh> loop;
  loop.attach(mesh);
  loop(static_cast<size_t>(steps));
  loop.detach();
  mesh.garbage_collection();
  const Eigen::MatrixXd rest = m.V;
  m.V.resize(static_cast<Eigen::Index>(mesh.n_vertices()), 3);
  for (const auto v : mesh.vertices()) {
    const auto p = mesh.point(v);
    m.V.row(v.idx()) << p[0], p[1], p[2];
  }
  for (const Eigen::Index i : unused) m.V.row(i) = rest.row(i);  // the first vertices keep their index
  m.F.resize(static_cast<Eigen::Index>(mesh.n_faces()), 3);
  for (const auto f : mesh.faces()) {
    int k = 0;
    for (const auto v : mesh.fv_range(f)) m.F(f.idx(), k++) = v.idx();
  }
  m.polygons.clear();
}

}  // namespace mbi::generate
