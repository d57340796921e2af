#pragma once
// Small helpers shared by the CLI and the runner: atomic text output and summaries as JSON.
#include <mbi/interp/metrics.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace mbi::scenes {

/// Writes `text` to `file` atomically (temporary file in the same folder, then rename).
/// Throws IoError naming the file.
void write_text_atomic(const std::filesystem::path& file, const std::string& text);

/// {"mean": ..., "std": ..., "max": ...} (inf/nan are written as null).
nlohmann::json summary_json(const mbi::interp::Summary& s);

/// {"bi": {...}, "modified_bi": {...}, "ratio": {...}, "faces": F} of a discontinuity table.
nlohmann::json disc_json(const mbi::interp::DiscontinuityTable& t);

/// Human-readable Table 2: rows Mean / StdDev / Max, columns BI, modified-BI, ratio.
std::string format_table(const mbi::interp::DiscontinuityTable& t);

}  // namespace mbi::scenes
