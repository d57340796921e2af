#pragma once
// What a 3D picture draws beside the model (internal): the run's colliders at a frame's time as
// slate-grey solids (pipeline::collider_mesh), and each plane (the ground) as a grey checked
// square under the model. A run without colliders or ground draws none of them.
#include <mbi/pipeline/colliders.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/raster/raster.hpp>

#include <Eigen/Geometry>

#include <vector>

namespace mbi::scenes {

/// The colour of a collider in the pictures (the model's is orange, the ground's grey).
inline const Eigen::Vector3d kColliderColor{0.68, 0.73, 0.85};

/// The colliders `pipe` steps with: contact = surface's (the ground the last), or contact =
/// control's ground plane as a plane collider; none for a run without a simulator.
std::vector<pipeline::Collider> picture_colliders(pipeline::FramePipeline& pipe);

/// The time (s) of pipe's last frame: its simulator's, 0 without one.
double picture_time(pipeline::FramePipeline& pipe);

/// The part near the model of what `colliders` (planes aside) cover at `time`: their bounds
/// clipped to `model` grown by half its largest side each way (empty when none is that near),
/// so that a picture frames a collider touching the model but not a large one far around it.
Eigen::AlignedBox3d near_bounds(const std::vector<pipeline::Collider>& colliders, double time,
                                const Eigen::AlignedBox3d& model);

/// `colliders` at `time` as seen through `view`: the solids first, then each plane as a checked
/// square about the view's centre, as large as the view's depth range lets a GPU picture keep it.
std::vector<raster::Solid> picture_solids(const std::vector<pipeline::Collider>& colliders, double time,
                                          const raster::View& view);

}  // namespace mbi::scenes
