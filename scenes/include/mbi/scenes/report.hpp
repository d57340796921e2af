#pragma once
// Reports shared by the command line and the runner: discontinuity summaries as JSON and text.
#include <mbi/interp/metrics.hpp>

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace mbi::scenes {

/// {"mean": ..., "std": ..., "max": ...} (inf/nan are written as null).
nlohmann::json summary_json(const mbi::interp::Summary& s);

/// {"bi": {...}, "modified_bi": {...}, "ratio": {...}, "faces": F} of a discontinuity table,
/// plus "phong": {...} and "phong_ratio": {...} (BI / Phong) when the table has a Phong column.
nlohmann::json disc_json(const mbi::interp::DiscontinuityTable& t);

/// {"position_rms", "position_max", "gradient_rms", "gradient_max", "size"} (interp::Accuracy).
nlohmann::json accuracy_json(const mbi::interp::Accuracy& a);

/// Human-readable Table 2: rows Mean / StdDev / Max, columns BI, modified-BI, ratio; with a
/// Phong column: BI, Phong, modified-BI, BI/Phong, BI/mod-BI.
std::string format_table(const mbi::interp::DiscontinuityTable& t);

/// Accuracy against a closed-form deformation, one row per named method: relative position
/// RMS / max (to the model size) and relative gradient RMS / max (to |Dg|).
std::string format_accuracy(
    const std::vector<std::pair<std::string, mbi::interp::Accuracy>>& rows);

}  // namespace mbi::scenes
