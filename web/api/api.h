#pragma once
// The page module's C API (the functions the page calls through Emscripten's cwrap; the
// native twin calls the same ones). One model at a time. Functions that can fail return 0 or
// -1 and leave the reason in mbi_error(). Pointers stay valid until the next call that changes
// the model (load, step, reset). Views: 0 BI, 1 modified-BI. Methods: 0 BI, 1 modified-BI.
#ifdef __cplusplus
extern "C" {
#endif

/// The scene files the page offers: scenes/*.toml, embedded at build time, by name
/// (mbi/web/scene_files.hpp); scenes are numbered 0 .. mbi_scene_count() - 1.
int mbi_scene_count(void);
/// A scene file's name, its stem (e.g. "twist-bar"); "" out of range.
const char* mbi_scene_name(int scene);
/// Why the page cannot run a scene file, "" when it can.
const char* mbi_scene_problem(int scene);
/// Loads a scene file at frame 0; 1 on success.
int mbi_load_scene(int scene);
/// Loads a scene file given as text (`bytes` long; the page's file input) at frame 0, parsed as
/// scenes/*.toml are, its messages naming `name`; 1 on success. A scene the page cannot run is
/// refused with the reason (mbi_scene_problem's).
int mbi_load_scene_text(const char* text, int bytes, const char* name);
/// The loaded scene's up direction (x, y, z: its output.up; y for an OBJ).
const double* mbi_up(void);
/// Loads an OBJ model from its text (`bytes` long) in a generated voxel cage of about
/// `control_vertices` vertices; 1 on success.
int mbi_load_obj(const char* text, int bytes, int control_vertices);
/// Why the last call failed ("" when it did not).
const char* mbi_error(void);
/// One line about the loaded scene.
const char* mbi_description(void);

/// Computes the next frame; its number, or -1 (the simulation failed: mbi_error()).
int mbi_step(void);
/// Back to frame 0.
int mbi_reset(void);
int mbi_set_method(int method);
int mbi_set_alpha(double alpha);
/// The current alpha of modified-BI (interp's default until set); 0 on failure.
double mbi_alpha(void);

/// Starts a poke where the ray (origin, direction; model coordinates) hits the view's surface;
/// 1 when it hit.
int mbi_grab(int view, double ox, double oy, double oz, double dx, double dy, double dz);
/// Moves the poke's target to where the ray meets the plane through the grabbed point that
/// faces it.
void mbi_move(double ox, double oy, double oz, double dx, double dy, double dz);
void mbi_release(void);

int mbi_vertex_count(void);
int mbi_triangle_count(void);
/// Triangles as 3 vertex indices each.
const int* mbi_triangles(void);
/// A view's dense positions, x y z per vertex.
const float* mbi_positions(int view);
/// Milliseconds of the last frame: drive (simulation), solve, Bezier, evaluate (the
/// pipeline's method), then the other view's evaluation.
const double* mbi_times(void);

/// Contact at the dense surface (contact = "surface"): the dense vertices inside a collider at
/// the current frame, as `mbi run` counts them; 0 without contact.
int mbi_touching_points(void);
/// The colliders (the scene's [[colliders]], then its ground plane with contact = "surface").
int mbi_collider_count(void);
/// Builds the colliders' triangles as they stand at the current frame (a plane as a square twice
/// the model's size); their number of vertices.
int mbi_collider_mesh(void);
/// After mbi_collider_mesh: x y z floats per vertex, 3 vertex indices per triangle.
const float* mbi_collider_positions(void);
const int* mbi_collider_triangles(void);
int mbi_collider_triangle_count(void);

/// 1: mbi_step evaluates the dense points on the CPU (at first); 0: the page evaluates them on
/// the GPU from mbi_bezier_texels, and mbi_positions evaluates a view on the CPU when asked.
int mbi_set_cpu_evaluation(int on);
/// Evaluates a view's dense points of the current frame on the CPU now; the milliseconds.
double mbi_evaluate_cpu(int view);
/// The GPU pass's inputs (gpu/gl/shaders/evaluate.glsl): per dense vertex its control element,
/// its barycentric coordinates (4 floats) and its rest position (3 floats); per view the current
/// Bezier control points minus the rest shape's, x y z 0 floats, mbi_bezier_rows() of them.
const int* mbi_point_elements(void);
const float* mbi_point_bary(void);
const float* mbi_rest_positions(void);
const float* mbi_bezier_texels(int view);
int mbi_bezier_rows(void);
/// The native viewer's crease colours for both views of the current frame (one scale); the
/// largest gradient jump (the scale's top), -1 on failure.
double mbi_update_creases(void);
/// A view's crease colours, RGB floats per dense vertex (after mbi_update_creases).
const float* mbi_crease_colors(int view);

/// The discontinuity table of the current frame (paper Table 2): the mean and largest face
/// energy E_F of BI, then of modified-BI, then the number of interior faces; null on failure.
const double* mbi_discontinuity(void);

/// Milliseconds per modified-BI solve at 448 control vertices (a 7 x 7 x 6 box cage, twisted),
/// the mean of `repeats` solves after one untimed.
double mbi_bench_solve(int repeats);

/// The page's cameras (mbi::interact::PerspectiveCamera; camera.cpp), any number of them,
/// independent of the loaded model. A new camera's handle (>= 0), or -1: the reason in mbi_camera_error().
int mbi_camera_new(double cx, double cy, double cz, double size, double ux, double uy, double uz, double yaw,
                   double pitch);
void mbi_camera_delete(int camera);
/// Why the last camera call failed ("" when it did not).
const char* mbi_camera_error(void);
/// A drag of (dx, dy) pixels, a wheel turn of dy; 0 for an unknown camera.
int mbi_camera_orbit(int camera, double dx, double dy);
int mbi_camera_zoom(int camera, double dy);
/// The eye, then the frame's forward, right and up: 12 doubles; null on failure.
const double* mbi_camera_pose(int camera);
/// Projection * view for a width x height viewport, 16 floats, column-major; null on failure.
const float* mbi_camera_matrix(int camera, int width, int height);
/// The ray through pixel (x, y) of a width x height view (y down): origin then direction, 6
/// doubles; null on failure.
const double* mbi_camera_ray(int camera, double x, double y, int width, int height);

#ifdef __cplusplus
}
#endif
