#pragma once
// Reports shared by the command line and the runner: discontinuity summaries as JSON and text.
#include <mbi/interp/metrics.hpp>

#include <nlohmann/json.hpp>

#include <string>

namespace mbi::scenes {

/// {"mean": ..., "std": ..., "max": ...} (inf/nan are written as null).
nlohmann::json summary_json(const mbi::interp::Summary& s);

/// {"bi": {...}, "modified_bi": {...}, "ratio": {...}, "faces": F} of a discontinuity table.
nlohmann::json disc_json(const mbi::interp::DiscontinuityTable& t);

/// Human-readable Table 2: rows Mean / StdDev / Max, columns BI, modified-BI, ratio.
std::string format_table(const mbi::interp::DiscontinuityTable& t);

}  // namespace mbi::scenes
