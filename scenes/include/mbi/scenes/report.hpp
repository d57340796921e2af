#pragma once
// Reports shared by the command line and the runner: discontinuity summaries as JSON and text.
#include <mbi/interp/metrics.hpp>

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace mbi::scenes {

/// x as JSON: a number when finite, else explicitly the string "inf", "-inf" or "nan" (never
/// the silent null that nlohmann writes for non-finite numbers). Only ratios with a zero
/// denominator can be inf: energies that overflow are an interp::OverflowError.
nlohmann::json number_json(double x);

/// {"mean": ..., "std": ..., "max": ...} (non-finite values as number_json writes them).
nlohmann::json summary_json(const mbi::interp::Summary& s);

/// The round-off level of face discontinuities on a control mesh with rest positions U (n x d):
/// 1e-20 L^(d-1), L its bounding-box diagonal. E_F integrates a squared gradient jump over a
/// face; at rest (X = U) it is round-off, about 1e-30 L^(d-1).
double disc_roundoff(const Eigen::Ref<const Eigen::MatrixXd>& U);

/// {"bi": {...}, "modified_bi": {...}, "ratio": {...}, "faces": F} of a discontinuity table,
/// plus "phong": {...} and "phong_ratio": {...} (BI / Phong) when the table has a Phong column.
/// A ratio's field is null (undefined) when its denominator (modified-BI, Phong) is at or below
/// `roundoff` (disc_roundoff): at rest both are round-off and their quotient is noise. Every
/// other value is a finite number (a non-finite one throws std::domain_error naming the key).
nlohmann::json disc_json(const mbi::interp::DiscontinuityTable& t, double roundoff = 0.0);

/// {"position_rms", "position_max", "gradient_rms", "gradient_max", "size"} (interp::Accuracy).
nlohmann::json accuracy_json(const mbi::interp::Accuracy& a);

/// Human-readable Table 2: rows Mean / StdDev / Max, columns BI, modified-BI, ratio; with a
/// Phong column: BI, Phong, modified-BI, BI/Phong, BI/mod-BI.
/// A ratio below `roundoff` (see disc_json) is shown as "-".
std::string format_table(const mbi::interp::DiscontinuityTable& t, double roundoff = 0.0);

/// Accuracy against a closed-form deformation, one row per named method: relative position
/// RMS / max (to the model size) and relative gradient RMS / max (to |Dg|).
std::string format_accuracy(
    const std::vector<std::pair<std::string, mbi::interp::Accuracy>>& rows);

}  // namespace mbi::scenes
