// The page module's C API (see api.h) over mbi::web::PageModel.
#include "api.h"

#include <mbi/base/timer.hpp>
#include <mbi/generate/procedural.hpp>
#include <mbi/interp/modified_bi.hpp>
#include <mbi/io/obj_text.hpp>
#include <mbi/web/page_model.hpp>
#include <mbi/web/scene_files.hpp>

#include <algorithm>
#include <exception>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace {

using mbi::web::PageModel;
using mbi::web::View;

std::optional<PageModel> g_model;
std::string g_error;
double g_times[5] = {0, 0, 0, 0, 0};
double g_table[5] = {0, 0, 0, 0, 0};
double g_up[3] = {0, 1, 0};
std::string g_text;  // the last string returned (mbi_scene_name, mbi_scene_problem)
Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> g_triangles;

// Runs f; on an exception keeps its message and returns `failed`.
template <class R, class F>
R guarded(F&& f, R failed) {
  g_error.clear();
  try {
    if (!g_model.has_value()) throw std::runtime_error("no model loaded");
    return f();
  } catch (const std::exception& e) {
    g_error = e.what();
  } catch (...) {
    g_error = "unknown error";
  }
  return failed;
}

int loaded(PageModel model) {
  g_model.emplace(std::move(model));
  g_triangles = g_model->triangles();
  return 1;
}

View view_of(int view) { return view == 0 ? View::BI : View::ModifiedBI; }

const mbi::web::SceneFile& scene_file(int scene) {
  const auto files = mbi::web::scene_files();
  if (scene < 0 || static_cast<std::size_t>(scene) >= files.size())
    throw std::out_of_range("no scene " + std::to_string(scene) + " (there are " + std::to_string(files.size()) + ")");
  return files[static_cast<std::size_t>(scene)];
}

// A scene file's problem on the page: page_problem(), or why it does not parse.
std::string problem_of(int scene) {
  try {
    return mbi::web::page_problem(mbi::web::parse(scene_file(scene)));
  } catch (const std::exception& e) {
    return e.what();
  }
}

// Loads the scene that parse() gives: 1, or 0 with its error kept for mbi_last_error.
template <class Parse>
int load_scene(Parse parse) {
  g_error.clear();
  try {
    const mbi::scenes::Scene s = parse();
    loaded(PageModel::scene(s));
    std::copy(s.output.up.data(), s.output.up.data() + 3, g_up);
    return 1;
  } catch (const std::exception& e) {
    g_error = e.what();
  }
  return 0;
}

}  // namespace

extern "C" {

int mbi_scene_count(void) { return static_cast<int>(mbi::web::scene_files().size()); }

const char* mbi_scene_name(int scene) {
  g_text = scene >= 0 && scene < mbi_scene_count() ? std::string(scene_file(scene).name) : "";
  return g_text.c_str();
}

const char* mbi_scene_problem(int scene) {
  g_text = problem_of(scene);
  return g_text.c_str();
}

int mbi_load_scene(int scene) {
  return load_scene([&] { return mbi::web::parse(scene_file(scene)); });
}

int mbi_load_scene_text(const char* text, int bytes, const char* name) {
  return load_scene(
      [&] { return mbi::scenes::parse_scene(std::string_view(text, static_cast<std::size_t>(bytes)), name); });
}

const double* mbi_up(void) { return g_up; }

int mbi_load_obj(const char* text, int bytes, int control_vertices) {
  g_error.clear();
  try {
    const mbi::io::SurfaceMesh m =
        mbi::io::parse_obj_text(std::string_view(text, static_cast<std::size_t>(bytes)), "model.obj");
    loaded(PageModel::surface(m.V, m.F, control_vertices));
    g_up[0] = g_up[2] = 0;
    g_up[1] = 1;
    return 1;
  } catch (const std::exception& e) {
    g_error = e.what();
  }
  return 0;
}

const char* mbi_error(void) { return g_error.c_str(); }
const char* mbi_description(void) { return g_model ? g_model->description().c_str() : ""; }

int mbi_step(void) {
  return guarded(
      [] {
        const bool ok = g_model->step();
        const mbi::pipeline::FrameTimings& t = g_model->timings();
        const double times[5] = {t.drive_ms, t.solve_ms, t.bezier_ms, t.evaluate_ms, g_model->other_view_ms()};
        std::copy(times, times + 5, g_times);
        if (!ok) throw std::runtime_error(g_model->message());
        return g_model->frame();
      },
      -1);
}

int mbi_reset(void) {
  return guarded([] { return g_model->reset(), 1; }, 0);
}

int mbi_set_method(int method) {
  return guarded(
      [method] {
        g_model->set_method(method == 0 ? mbi::pipeline::Method::BI : mbi::pipeline::Method::ModifiedBI);
        return 1;
      },
      0);
}

int mbi_set_alpha(double alpha) {
  return guarded([alpha] { return g_model->set_alpha(alpha), 1; }, 0);
}

double mbi_alpha(void) {
  return guarded([] { return g_model->alpha(); }, 0.0);
}

int mbi_grab(int view, double ox, double oy, double oz, double dx, double dy, double dz) {
  return guarded(
      [=] {
        return g_model->grab(view_of(view), {Eigen::Vector3d(ox, oy, oz), Eigen::Vector3d(dx, dy, dz)}) ? 1 : 0;
      },
      0);
}

void mbi_move(double ox, double oy, double oz, double dx, double dy, double dz) {
  guarded([=] { return g_model->move({Eigen::Vector3d(ox, oy, oz), Eigen::Vector3d(dx, dy, dz)}), 1; }, 0);
}

void mbi_release(void) {
  guarded([] { return g_model->release(), 1; }, 0);
}

int mbi_vertex_count(void) { return g_model ? g_model->vertices() : 0; }
int mbi_triangle_count(void) { return static_cast<int>(g_triangles.rows()); }
const int* mbi_triangles(void) { return g_triangles.data(); }
const float* mbi_positions(int view) {
  return guarded([view] { return g_model->positions(view_of(view)).data(); }, static_cast<const float*>(nullptr));
}
const double* mbi_times(void) { return g_times; }

int mbi_touching_points(void) { return g_model ? g_model->touching_points() : 0; }
int mbi_collider_count(void) { return g_model ? g_model->colliders() : 0; }

int mbi_collider_mesh(void) {
  return guarded([] { return static_cast<int>(g_model->update_collider_mesh().positions.size() / 3); }, 0);
}

const float* mbi_collider_positions(void) { return g_model ? g_model->collider_mesh().positions.data() : nullptr; }
const int* mbi_collider_triangles(void) { return g_model ? g_model->collider_mesh().indices.data() : nullptr; }
int mbi_collider_triangle_count(void) {
  return g_model ? static_cast<int>(g_model->collider_mesh().indices.size() / 3) : 0;
}

int mbi_set_cpu_evaluation(int on) {
  return guarded([on] { return g_model->set_cpu_evaluation(on != 0), 1; }, 0);
}

double mbi_evaluate_cpu(int view) {
  return guarded([view] { return g_model->evaluate_cpu(view_of(view)); }, -1.0);
}

const int* mbi_point_elements(void) { return g_model ? g_model->point_elements().data() : nullptr; }
const float* mbi_point_bary(void) { return g_model ? g_model->point_bary().data() : nullptr; }
const float* mbi_rest_positions(void) { return g_model ? g_model->rest_positions().data() : nullptr; }

const float* mbi_bezier_texels(int view) {
  return guarded([view] { return g_model->bezier_texels(view_of(view)).data(); }, static_cast<const float*>(nullptr));
}

int mbi_bezier_rows(void) {
  if (!g_model) return 0;
  const Eigen::MatrixXi& T = g_model->control_elements();  // K = (d + 1)(d + 2) / 2 per element
  return static_cast<int>(T.rows() * T.cols() * (T.cols() + 1) / 2);
}

double mbi_update_creases(void) {
  return guarded([] { return g_model->update_creases(); }, -1.0);
}

const float* mbi_crease_colors(int view) { return g_model ? g_model->crease_colors(view_of(view)).data() : nullptr; }

const double* mbi_discontinuity(void) {
  return guarded(
      [] {
        const mbi::interp::DiscontinuityTable t = g_model->discontinuity();
        const double table[5] = {t.bi.mean, t.bi.max, t.modified_bi.mean, t.modified_bi.max, double(t.faces)};
        std::copy(table, table + 5, g_table);
        return static_cast<const double*>(g_table);
      },
      static_cast<const double*>(nullptr));
}

double mbi_bench_solve(int repeats) {
  Eigen::MatrixXd U, X;
  Eigen::MatrixXi T;
  const Eigen::Vector3i n(7, 7, 6);  // 8 x 8 x 7 = 448 vertices, as mbi-bench's box_cage(450)
  mbi::generate::box_tets(Eigen::Vector3d::Zero(), n.cast<double>(), n, U, T);
  X = mbi::generate::twist_bend(U, 0.5 * n.x(), 0.5 * n.y(), 0, n.z(), 1.2, 0.1);
  const mbi::interp::ModifiedBI solver(U, T);
  mbi::interp::VertexMatrices M = solver.solve(X);
  const auto t0 = mbi::Clock::now();
  for (int k = 0; k < repeats; ++k) M = solver.solve(X);
  return mbi::ms_since(t0) / std::max(repeats, 1);
}

}  // extern "C"
