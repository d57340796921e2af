// The stand-in for subdivide.cpp in a build without OpenMesh (MBI_WITH_OPENMESH=OFF).
#include <mbi/error.hpp>
#include <mbi/generate/subdivide.hpp>

namespace mbi::generate {

void loop_subdivide(io::SurfaceMesh&, int steps) {
  if (steps > 0) throw mbi::Error("Loop subdivision needs OpenMesh, which this build leaves out");
}

}  // namespace mbi::generate
