#pragma once
// Contact for a simulated frame pipeline: where it acts (the control mesh's nodes through the
// simulator's ground plane, or the dense surface through the embedding's transpose) and the
// SurfaceContact of a simulation built with the interpolation method in use (method.md fact 16).
//
//   SurfaceContactOptions o{.colliders = {Collider::plane({0, 0, 0}, {0, 1, 0})}};
//   driver.set_contact(make_surface_contact(U, T, P, pipeline_options, o, masses.sum(), gravity));
//
// Units: m, kg, m/s^2, N/m.
#include <mbi/base/names.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <memory>
#include <optional>
#include <vector>

namespace mbi::pipeline {

/// Control: the simulator's ground plane projects the control nodes (the cage's margin floats
/// above it). Surface: the dense points touch colliders (SurfaceContact).
enum class ContactMode { Control, Surface };
inline constexpr auto kContactModeNames =
    name_table<ContactMode>({{ContactMode::Control, "control"}, {ContactMode::Surface, "surface"}});

/// The penalty stiffness (N/m per point) that holds the body's whole weight on a single point
/// 1e-4 of the diagonal deep: 1e4 m g / L, m the body's mass (kg), g = |gravity| (9.81 m/s^2
/// without gravity), L the dense model's bounding-box diagonal (m). With more points touching,
/// each sinks less (the weight is shared). Throws Error on a non-positive mass or diagonal.
double default_contact_stiffness(double mass, const Eigen::Vector3d& gravity, double diagonal);

struct SurfaceContactOptions {
  std::vector<Collider> colliders;
  std::optional<double> stiffness;  ///< N/m per point; default_contact_stiffness when unset
  std::vector<int> points;          ///< rows of P that touch (sorted); empty = every row
  std::optional<double> max_depth;          ///< m; SurfaceContact::set_max_depth when set
  std::optional<double> friction_velocity;  ///< m/s; SurfaceContact::set_friction_velocity when set
};

/// SurfaceContact of the dense rest points P (p x 3, the pipeline's points) in the control mesh
/// (U, T), evaluated with the pipeline's method and interpolation options, so that contact acts
/// where the written surface is. mass (kg) and gravity (m/s^2) give the default stiffness.
/// Throws Error on a bad collider ("collider i: ..."), stiffness or point index.
std::shared_ptr<SurfaceContact> make_surface_contact(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                                     const Eigen::Ref<const Eigen::MatrixXi>& T,
                                                     const Eigen::Ref<const Eigen::MatrixXd>& P,
                                                     const PipelineOptions& pipeline,
                                                     const SurfaceContactOptions& options, double mass,
                                                     const Eigen::Vector3d& gravity);

/// The contact points inside some collider (signed distance < 0) at node positions X (n x 3), at
/// the contact's current time.
int touching_points(const SurfaceContact& contact, const Eigen::Ref<const Eigen::MatrixXd>& X);

}  // namespace mbi::pipeline
