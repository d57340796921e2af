// mbi deform: the interpolation as a command-line tool, for users with their own simulator.
//
//   mbi deform --control REST --deformed X --mesh DENSE --out OUT [--mesh DENSE2 --out OUT2 ...]
//              [--method bi|modified-bi|phong] [--alpha A] [--pin-boundary] [--stats STATS.json]
//              [--max-memory 8G]
//   mbi deform --control REST --deformed TRAJECTORY --mesh DENSE --out CACHE|GLTF|NUMBERED ...
//   mbi deform --example twist-bar [--out OUT] [--stats STATS.json]
//
// One pose is a trajectory of one frame (deform.hpp). Prints the face discontinuity of BI, Phong
// and modified-BI side by side at the last frame, and for --example the error of each against the
// closed-form deformation.
#include "commands.hpp"
#include "deform.hpp"
#include "deform_outputs.hpp"

#include <mbi/error.hpp>
#include <mbi/interp/memory.hpp>
#include <mbi/pipeline/method.hpp>

#include <memory>
#include <stdexcept>
#include <string>

namespace mbi::cli {
namespace {

const Registrar reg{
    "deform", "Deform a dense mesh by a deformed control mesh (modified-BI, Phong or BI)",
    [](CLI::App& sub) -> Action {
      auto a = std::make_shared<DeformArgs>();
      sub.add_option("--control", a->control,
                     "REQUIRED (unless --example) rest control mesh: TetGen .node/.ele (or base name), Gmsh .msh "
                     "or legacy VTK .vtk");
      sub.add_option("--deformed", a->deformed,
                     "REQUIRED (unless --example) deformed control positions, one per control node in file order: "
                     ".node, .msh, .vtk, .vtu or plain text (n lines of d numbers); or a whole trajectory: .pc2, .mdd, "
                     ".pvd, numbered files x_%04d.vtk or a quoted glob 'x_*.vtk'");
      sub.add_option("--mesh", a->meshes,
                     "REQUIRED (unless --example) dense model: .obj/.ply/.off/.stl/.glb/.gltf, or points .txt/.xyz; "
                     "repeat it for several models driven by one control mesh, each with its --out");
      sub.add_option("--out", a->outs,
                     "REQUIRED (unless --example) output of each --mesh, format by extension: .obj/.ply/.off/.stl/.glb/"
                     ".gltf (keeping the input's attributes when the format is the same) or points .txt/.xyz; for a "
                     "trajectory a point cache .pc2/.mdd, an animated glTF .glb/.gltf or numbered files out_%04d.obj");
      sub.add_option("--displacement", a->displacement,
                     "point field of the --deformed .vtu/.vtk files added to their positions (a rest mesh with a "
                     "displacement, as FEniCS and deal.II write)")
          ->check([](const std::string& s) { return s.empty() ? std::string("give the point field's name") : std::string(); });
      add_choice(sub, "--method", a->method, pipeline::kMethodNames, "interpolation");
      sub.add_option_function<double>(
          "--alpha", [a](double v) { a->alpha = v; }, "weight of E_vibr (> 0; default 0.1 in 3D, 0.2 in 2D)");
      sub.add_flag("--pin-boundary", a->pin_boundary, "M = 0 on the control mesh boundary");
      sub.add_option("--stats", a->stats, "write statistics and timings as JSON");
      sub.add_option("--max-outside", a->max_outside,
                     "refuse dense points farther outside the control mesh than this times the model size");
      sub.add_option_function<std::string>(
          "--fps",
          [a](const std::string& s) {
            try {
              a->fps = parse_fps(s);
            } catch (const std::runtime_error& e) {
              throw CLI::ValidationError(e.what());
            }
          },
          "output frame rate: the sequence resampled to it from its frame times (an MDD or a .pvd), positions "
          "interpolated linearly between input frames; without it the frames are kept as they are (24 fps where "
          "times meet frame numbers)");
      sub.add_option_function<std::string>(
          "--max-memory",
          [a](const std::string& s) {
            try {
              a->max_memory = interp::parse_memory_size(s);
            } catch (const mbi::Error& e) {
              throw CLI::ValidationError(std::string("--max-memory: ") + e.what());
            }
          },
          "memory the run may take, e.g. 8G or 512M (K, M, G, T: powers of 1024); a control mesh whose estimated "
          "peak (the factor's symbolic analysis, before any numeric work) exceeds it is refused, naming the sizes. "
          "Default: MemAvailable of /proc/meminfo");
      sub.add_flag("--force", a->force, "overwrite existing --out / --stats files");
      sub.add_option("--example", a->example, "built-in example instead of files: twist-bar");
      add_threads_option(sub);
      return [a] { return run_deform(*a); };
    }};

}  // namespace
}  // namespace mbi::cli
