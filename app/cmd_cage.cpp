// mbi cage DENSE --vertices N --out BASE [--stats STATS.json] [--mesher voxel|tetgen]: builds a
// control mesh around a dense surface and writes BASE.node / BASE.ele (TetGen format).
#include "commands.hpp"

#include <mbi/generate/cage.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/io/io.hpp>

#include <nlohmann/json.hpp>

#include <cctype>
#include <cstdio>
#include <filesystem>

namespace {

const mbi::cli::Registrar reg(
    "cage", "Build a coarse control mesh (tetrahedra; triangles for planar input) around a dense "
            "surface",
    [](CLI::App& sub) -> mbi::cli::Action {
      struct Args {
        std::string dense, out, stats, vtk, mesher = "voxel";
        int vertices = 200;
        bool force_3d = false;
      };
      auto a = std::make_shared<Args>();
      sub.add_option("dense", a->dense, "dense surface (.obj, .off, .ply, .stl)")->required();
      sub.add_option("--vertices,-n", a->vertices, "target number of control vertices (8 or more)")
          ->required()
          ->check(CLI::Range(8, 1000000));
      sub.add_option("--out,-o", a->out, "output base name: writes BASE.node and BASE.ele (and removes a stale BASE.face, .edge, .neigh)")
          ->required();
      sub.add_option("--stats", a->stats, "write statistics as JSON to this file");
      sub.add_option("--vtk", a->vtk, "also write the control mesh as legacy VTK");
      sub.add_flag("--force-3d", a->force_3d, "tetrahedra even for a planar input");
      sub.add_option("--mesher", a->mesher,
                     "voxel: 6 Kuhn tetrahedra per envelope cell (default); tetgen: the "
                     "envelope's boundary tetrahedralised by TetGen (3D)")
          ->check(CLI::IsMember({"voxel", "tetgen"}));
      return [a]() {
        const mbi::io::SurfaceMesh dense = mbi::io::read_surface(a->dense);
        mbi::generate::CageOptions opt;
        opt.target_vertices = a->vertices;
        opt.force_3d = a->force_3d;
        opt.mesher = mbi::generate::parse_mesher(a->mesher);
        const mbi::generate::CageResult cage = mbi::generate::make_cage(dense.V, dense.F, opt);
        mbi::io::write_tetgen(a->out, cage.U, cage.T);
        // TetGen companions of BASE left from an earlier mesh would not match this one: they go
        std::filesystem::path base(a->out);
        std::string ext = base.extension().string();
        for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (ext == ".node" || ext == ".ele" || ext == ".face") base.replace_extension();
        for (const char* companion : {".face", ".edge", ".neigh"}) {
          std::filesystem::path p = base;
          p += companion;
          std::error_code ec;
          if (std::filesystem::is_regular_file(p, ec) && std::filesystem::remove(p, ec))
            std::fprintf(stderr, "mbi cage: note: removed %s (left from an earlier mesh)\n",
                         p.string().c_str());
        }
        if (!a->vtk.empty()) mbi::io::write_vtk(a->vtk, cage.U, cage.T);
        nlohmann::json j;
        j["input"] = a->dense;
        j["dense_vertices"] = dense.V.rows();
        j["target_vertices"] = a->vertices;
        j["mesher"] = mbi::generate::mesher_name(cage.mesher);
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
        if (!a->stats.empty()) mbi::io::write_text_atomic(a->stats, j.dump(2) + "\n");
        std::printf("%s (%s): %lld control vertices, %lld %s, min angle %.2f deg, %d outside, %.3f s\n",
                    a->out.c_str(), mbi::generate::mesher_name(cage.mesher),
                    static_cast<long long>(cage.U.rows()),
                    static_cast<long long>(cage.T.rows()),
                    cage.dim() == 3 ? "tetrahedra" : "triangles", cage.min_dihedral_deg,
                    cage.outside_points, cage.seconds);
        return 0;
      };
    });

}  // namespace
