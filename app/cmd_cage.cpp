// mbi cage DENSE... --vertices N --out BASE [--stats STATS.json] [--mesher voxel|tetgen]: builds a
// control mesh around one or several dense surfaces and writes BASE.node / BASE.ele (TetGen).
#include "commands.hpp"
#include "deform_parts.hpp"
#include "signals.hpp"

#include <mbi/generate/cage.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/io/io.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace mbi::cli {
namespace {

struct CageArgs {
  std::string first_dense, out, stats, vtk;
  std::vector<std::string> dense;  // the first and the others
  generate::Mesher mesher = generate::Mesher::Voxel;
  int vertices = 200;
  bool force_3d = false, force = false;
};

// BASE, without a .node/.ele/.face extension; a folder's name ("dir/", ".") is refused (it would
// make ".node" in the folder, or hidden "..node").
fs::path base_name(const std::string& out) {
  fs::path base(out);
  const std::string ext = io::lower_extension(base);
  if (ext == ".node" || ext == ".ele" || ext == ".face") base.replace_extension();
  io::check_file_name(base, "--out");
  return base;
}

nlohmann::json stats_json(const CageArgs& a, const io::SurfaceMesh& dense, const generate::CageResult& cage) {
  nlohmann::json j;
  j["input"] = a.dense.size() == 1 ? nlohmann::json(a.dense[0]) : nlohmann::json(a.dense);
  j["dense_vertices"] = dense.V.rows();
  j["target_vertices"] = a.vertices;
  j["mesher"] = generate::mesher_name(cage.mesher);
  if (!cage.tetgen_switches.empty()) j["tetgen_switches"] = cage.tetgen_switches;
  j["dim"] = cage.dim();
  j["vertices"] = cage.U.rows();
  j["tetrahedra"] = cage.dim() == 3 ? cage.T.rows() : 0;
  j["triangles"] = cage.dim() == 2 ? cage.T.rows() : 0;
  j["elements"] = cage.T.rows();
  j["cell_size"] = cage.cell_size;
  j["min_dihedral_deg"] = cage.min_dihedral_deg;
  j["outside_points"] = cage.outside_points;
  j["seconds"] = cage.seconds;
  return j;
}

// TetGen companions of BASE left from an earlier mesh would not match this one: they go (but not
// one that --stats or --vtk named).
void remove_stale_companions(const CageArgs& a, const fs::path& base) {
  for (const char* companion : {".face", ".edge", ".neigh"}) {
    fs::path p = base;
    p += companion;
    std::error_code ec;
    bool ours = false;
    for (const std::string& o : {a.stats, a.vtk})
      if (!o.empty() && fs::equivalent(p, o, ec)) ours = true;
    if (!ours && fs::is_regular_file(fs::symlink_status(p, ec)) && fs::remove(p, ec))
      std::fprintf(stderr, "mbi cage: note: removed %s (left from an earlier mesh)\n", p.string().c_str());
  }
}

generate::CageResult make_cage(const CageArgs& a, const DenseParts& parts, const io::SurfaceMesh& dense) {
  generate::CageOptions opt;
  opt.target_vertices = a.vertices;
  opt.force_3d = a.force_3d;
  opt.mesher = a.mesher;
  if (opt.mesher == generate::Mesher::TetGen && !a.force_3d && generate::is_planar(dense.V))
    throw std::runtime_error(parts.names() + ": the model is flat (every z = " + std::to_string(dense.V(0, 2)) +
                             "), a 2D input; TetGen makes tetrahedra only: use the voxel mesher (the default) "
                             "for a 2D triangle cage, or --force-3d for tetrahedra");
  return generate::make_cage(dense.V, dense.F, opt);
}

int run_cage(CageArgs a) {
  handle_interrupts(nullptr);  // all or nothing: a signal ends it at once
  a.dense.insert(a.dense.begin(), a.first_dense);
  const fs::path base = base_name(a.out);
  fs::path node = base, ele = base;
  node += ".node";
  ele += ".ele";
  // Every output checked and reserved before any work; all written at the end, or none.
  io::OutputSet outputs({a.dense.begin(), a.dense.end()}, a.force);
  const std::size_t i_node = outputs.add(node, "--out");
  outputs.add(ele, "--out", i_node);
  const std::size_t i_stats = a.stats.empty() ? 0 : outputs.add(a.stats, "--stats");
  const std::size_t i_vtk = a.vtk.empty() ? 0 : outputs.add(a.vtk, "--vtk");
  const DenseParts parts = read_dense_parts(a.dense);
  const io::SurfaceMesh dense = parts.joined();
  const generate::CageResult cage = make_cage(a, parts, dense);
  outputs.write(i_node, [&](const fs::path& p) { io::write_tetgen(p, cage.U, cage.T); });
  if (!a.vtk.empty()) outputs.write(i_vtk, [&](const fs::path& p) { io::write_vtk(p, cage.U, cage.T); });
  if (!a.stats.empty()) {
    const nlohmann::json j = stats_json(a, dense, cage);
    check_finite(j, a.stats);
    outputs.write(i_stats, [&](const fs::path& p) { io::write_text_atomic(p, j.dump(2) + "\n"); });
  }
  outputs.commit();
  remove_stale_companions(a, base);
  std::printf("%s (%s): %lld control vertices, %lld %s, min angle %.2f deg, %d outside, %.3f s\n", a.out.c_str(),
              generate::mesher_name(cage.mesher), static_cast<long long>(cage.U.rows()),
              static_cast<long long>(cage.T.rows()), cage.dim() == 3 ? "tetrahedra" : "triangles",
              cage.min_dihedral_deg, cage.outside_points, cage.seconds);
  return 0;
}

const Registrar reg{
    "cage", "Build a coarse control mesh (tetrahedra; triangles for planar input) around a dense surface",
    [](CLI::App& sub) -> Action {
      auto a = std::make_shared<CageArgs>();
      sub.add_option("dense", a->first_dense, "dense surface (.obj, .off, .ply, .stl, .glb, .gltf)")->required();
      sub.add_option("more", a->dense, "more dense surfaces: the cage encloses all of them");
      sub.add_option("--vertices,-n", a->vertices, "target number of control vertices (8 or more)")
          ->required()
          ->check(CLI::Range(8, 1000000));
      sub.add_option("--out,-o", a->out,
                     "output base name: writes BASE.node and BASE.ele (and removes a stale BASE.face, .edge, .neigh)")
          ->required();
      sub.add_option("--stats", a->stats, "write statistics as JSON to this file");
      sub.add_option("--vtk", a->vtk, "also write the control mesh as legacy VTK");
      sub.add_flag("--force-3d", a->force_3d, "tetrahedra even for a planar input");
      add_choice(sub, "--mesher", a->mesher, generate::kMesherNames,
                 "voxel: 6 Kuhn tetrahedra per envelope cell (default); tetgen: the "
                 "envelope's boundary tetrahedralised by TetGen (3D)");
      sub.add_flag("--force", a->force, "overwrite existing outputs (BASE.node/.ele, --stats, --vtk); inputs never");
      add_threads_option(sub);
      return [a] { return run_cage(*a); };
    }};

}  // namespace
}  // namespace mbi::cli
