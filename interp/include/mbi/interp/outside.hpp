#pragma once
// Dense points outside the control mesh: the warning every door gives for them and the
// max-outside check (mbi deform --max-outside, Python's max_outside=) that refuses those too far
// out. Eigen only; no threads; nothing here allocates more than a message.
#include <mbi/interp/embed.hpp>

#include <string>

namespace mbi::interp {

/// Returns tolerance (a multiple of the model size) when it is a finite number >= 0; throws
/// Error otherwise ("max_outside must be ...": a door names its own option around it).
double check_max_outside(double tolerance);

/// The points of an embedding farther outside the mesh than a tolerance x the model size.
struct FarPoints {
  int count = 0;              ///< how many
  int points = 0;             ///< of how many (emb.size())
  int worst = -1;             ///< the farthest one's row of P; -1 when count is 0
  double worst_distance = 0;  ///< its distance to the mesh, in P's units
  double tolerance = 0;       ///< the tolerance asked (x the model size)
  double model_size = 0;      ///< the diagonal of P's bounding box
  double limit = 0;           ///< tolerance x model_size
};

/// P: the p x d points emb was made from (p = emb.size(); throws Error otherwise, and as
/// check_max_outside for the tolerance). Distances are emb.outside_distance. Cost O(p d).
FarPoints far_points(const Embedding& emb, const Eigen::Ref<const Eigen::MatrixXd>& P, double tolerance);

/// The refusal, one sentence: "k of n points lie farther outside the control mesh CONTROL than
/// OPTION t x the model size ...; the worst, point w, by ...". option: how the door spells the
/// tolerance ("--max-outside ", "max_outside=").
std::string far_points_message(const FarPoints& far, const std::string& option, const std::string& control);

/// The warning for an embedding with outside points: "k of n points lie outside the control mesh
/// (farthest d); they follow the nearest element by extrapolation". Empty when none is outside.
std::string outside_message(const Embedding& emb);

}  // namespace mbi::interp
