// mbi run SCENE [--out DIR] [--frames N] [--mesh FILE] [--method bi|modified-bi|phong]
//         [--gpu auto|on|off] [--creases] [--force] [--quiet] [--threads N]
#include "commands.hpp"
#include "signals.hpp"

#include <mbi/scenes/output_folder.hpp>
#include <mbi/scenes/report.hpp>
#include <mbi/scenes/runner.hpp>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

namespace mbi::cli {
namespace {

struct RunArgs {
  std::string scene, out, mesh;
  std::optional<pipeline::Method> method;
  std::optional<scenes::GpuUse> gpu;
  int frames = 0;
  bool force = false, quiet = false, force_3d = false, creases = false;
};

int run_run(const RunArgs& a) {
  scenes::Scene sc = scenes::load_scene(a.scene);
  if (a.creases) sc.output.creases = true;
  scenes::output_folder(sc, a.out);  // a name that cannot be a folder fails here, before work
  scenes::RunOptions o;
  o.out_dir = a.out;
  o.frames = a.frames;
  o.mesh = a.mesh;
  o.method = a.method;
  o.gpu = a.gpu;
  o.warn = [](const std::string& s) { std::fprintf(stderr, "mbi run: %s\n", s.c_str()); };
  o.force = a.force;
  o.force_3d = a.force_3d;
  const bool tty = isatty(fileno(stderr));
  const auto t0 = std::chrono::steady_clock::now();
  int last_pct = -1;
  if (!a.quiet) {
    o.log = [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); };
    o.progress = [&](int f, int total) {
      const int pct = total > 0 ? 100 * f / total : 100;
      const double s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (tty) {
        const int w = 30, filled = w * pct / 100;
        std::fprintf(stderr, "\r[%s%s] %3d%%  frame %d/%d  %.1f s", std::string(filled, '#').c_str(),
                     std::string(w - filled, ' ').c_str(), pct, f, total, s);
        if (f == total) std::fprintf(stderr, "\n");
      } else if (pct / 10 != last_pct / 10 || f == total) {
        std::fprintf(stderr, "frame %d/%d (%d%%) %.1f s\n", f, total, pct, s);
      }
      last_pct = pct;
    };
  }
  static std::atomic<int> stop{0};  // the signal that stops the run (signals.hpp)
  o.stop = &stop;
  handle_interrupts(&stop);
  const scenes::RunResult r = scenes::run_scene(sc, o);
  if (tty && (r.failed || r.interrupted) && !a.quiet) std::fprintf(stderr, "\n");
  if (r.interrupted && r.frames < 0) {
    std::fprintf(stderr, "mbi run: interrupted by %s while loading; nothing written\n",
                 scenes::signal_name(r.interrupted).c_str());
    return 128 + r.interrupted;
  }
  std::printf("scene %s: %d frames, outputs in %s (evaluated on %s)\n", sc.name.c_str(), r.frames,
              r.out_dir.string().c_str(), r.evaluator.c_str());
  std::printf("face discontinuity at the last frame (%d interior faces):\n%s", r.last_table.faces,
              scenes::format_table(r.last_table, r.roundoff).c_str());
  if (r.failed) {
    std::fprintf(stderr, "mbi run: error: %s (outputs up to frame %d kept)\n", r.message.c_str(),
                 r.frames);
    return 3;
  }
  if (r.interrupted) {
    std::fprintf(stderr, "mbi run: interrupted by %s after frame %d; outputs up to frame %d finished\n",
                 scenes::signal_name(r.interrupted).c_str(), r.frames, r.frames);
    return 128 + r.interrupted;
  }
  return 0;
}

const Registrar reg{
    "run", "Run a scene file headless and write meshes, point cache, pictures and metrics",
    [](CLI::App& sub) -> Action {
      auto a = std::make_shared<RunArgs>();
      sub.add_option("scene", a->scene, "scene file (.toml)")->required();
      sub.add_option("--out", a->out, "output folder (default out/<scene name>)");
      sub.add_option("--frames", a->frames, "number of frames (default: the scene's)")
          ->check(CLI::Range(1, 1000000));
      sub.add_option("--mesh", a->mesh, "dense model replacing the scene's (.obj/.ply/.off/.stl)");
      add_choice(sub, "--method", a->method, pipeline::kMethodNames, "interpolation replacing the scene's");
      add_choice(sub, "--gpu", a->gpu, scenes::kGpuUseNames,
                 "evaluate and draw on the GPU: auto (when OpenGL is available, else the CPU, "
                 "saying so), on (error without OpenGL), off (CPU, double); default: the "
                 "scene's interpolation.gpu, auto");
      sub.add_flag("--creases", a->creases,
                   "3D pictures coloured by the jump of the deformation gradient at the control faces, "
                   "with a legend (the scene's output.creases)");
      sub.add_flag("--force", a->force, "overwrite a non-empty output folder");
      sub.add_flag("--quiet", a->quiet, "no progress output");
      sub.add_flag("--force-3d", a->force_3d,
                   "a flat model (every z equal) stays 3D (default: it runs in 2D)");
      add_threads_option(sub);
      return [a] { return run_run(*a); };
    }};

}  // namespace
}  // namespace mbi::cli
