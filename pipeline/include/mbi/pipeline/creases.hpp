#pragma once
// The creases in colour: how large the jump of the deformation gradient is across each interior
// control face (the per-face quantity of the discontinuity table, interp/metrics.hpp), carried
// to the dense points, and the colour scale the viewer and `mbi run`'s pictures share.
#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include <Eigen/Core>

#include <string>

namespace mbi::pipeline {

/// What the colours show (the legend's title): the RMS over a face of ||[grad x]||_F, the jump
/// of the deformation gradient across it, sqrt(E_F / |F|); dimensionless (a strain).
inline constexpr const char* kCreaseQuantity = "gradient jump |[grad x]| (RMS over a face, strain)";

/// A band of this width (in barycentric coordinates: a fraction of the element's height) along
/// each interior face takes its colour: the jump lives on the face, so each crease reads as a line.
inline constexpr double kCreaseBand = 0.2;

class Creases {
 public:
  /// U n x d rest control positions, T m x (d+1) elements. Keeps references to both.
  Creases(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T);
  /// The number of interior faces (of face_jumps' vectors).
  Eigen::Index faces() const { return area_.size(); }

  /// One entry per row of interp::interior_faces(T): sqrt(E_F / |F|) of the field (X, M)
  /// (M = 0: BI), with E_F of interp::face_discontinuity.
  Eigen::VectorXd face_jumps(const Eigen::Ref<const Eigen::MatrixXd>& X,
                             const interp::VertexMatrices& M) const;
  /// face_jumps of the pipeline's current frame with `method` (its M solved on demand).
  Eigen::VectorXd face_jumps(FramePipeline& pipe, Method method) const;
  /// One entry per dense point of emb (embedded in U, T): the largest of jump_f (1 - b_f / kCreaseBand) over the interior
  /// faces f of its element, b_f its barycentric coordinate of the vertex opposite f (0 on f).
  Eigen::VectorXd point_values(const interp::Embedding& emb, const Eigen::Ref<const Eigen::VectorXd>& jumps) const;
  /// Per dense point of emb: whether it lies in the band of an interior face (the creases show there).
  std::vector<bool> near_faces(const interp::Embedding& emb) const;

 private:
  const Eigen::MatrixXd& U_;
  const Eigen::MatrixXi& T_;
  Eigen::VectorXd area_;       ///< per interior face, rest area (2D: length)
  Eigen::MatrixXi opposite_;   ///< m x (d+1): the interior face opposite each vertex, -1 on the boundary
};

/// The colour (RGB in 0..1) of t in [0, 1] (clamped): cool blue-grey at 0, orange at 0.5, hot red
/// at 1; red minus blue grows with t, so "hotter" is measurable from pixels.
Eigen::Vector3d crease_color(double t);

/// The top of the shared scale for values up to `largest`: largest, at least kCreaseFloor.
double crease_scale(double largest);
/// The smallest top of the scale: a jump of 0.1% strain; below it (round-off at rest) all is cold.
inline constexpr double kCreaseFloor = 1e-3;

/// A legend number: 3 significant digits ("0", "0.0423", "1.2e-05").
std::string crease_number(double v);

}  // namespace mbi::pipeline
