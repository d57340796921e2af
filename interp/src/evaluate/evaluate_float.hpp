#pragma once
// interp::evaluate<float>'s 3D positions on FastEvaluator's kernels (internal; evaluate_float.cpp).
#include <mbi/interp/embed.hpp>
#include <mbi/interp/evaluate.hpp>

namespace mbi::interp::detail {

/// Positions (p x 3, inner stride 1, shapes checked by the caller) of every embedded point from B
/// ((m 10) x 3); on up to `threads` threads (0: the library's count). Throws Error naming the first
/// point whose element is not one of B's (positions are then unspecified).
void evaluate_float3(const MatrixIn& B, const Embedding& emb, PointsRef<float> positions, int threads);

}  // namespace mbi::interp::detail
