#pragma once
// Smooth densification of a triangle surface (Loop subdivision, OpenMesh).
#include <mbi/io/io.hpp>

namespace mbi::generate {

/// Applies `steps` Loop subdivision steps to a manifold triangle surface (3D). The first
/// vertices keep their index; a vertex no face uses keeps its position (Loop does not move it).
/// Throws mbi::Error naming the number of non-manifold faces if the surface is not manifold.
void loop_subdivide(io::SurfaceMesh& mesh, int steps);

}  // namespace mbi::generate
