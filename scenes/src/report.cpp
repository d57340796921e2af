#include <mbi/scenes/report.hpp>

#include <cstdio>
#include <sstream>

namespace mbi::scenes {

nlohmann::json summary_json(const mbi::interp::Summary& s) {
  return {{"mean", s.mean}, {"std", s.std}, {"max", s.max}};
}

nlohmann::json disc_json(const mbi::interp::DiscontinuityTable& t) {
  nlohmann::json j = {{"bi", summary_json(t.bi)},
                      {"modified_bi", summary_json(t.modified_bi)},
                      {"ratio", summary_json(t.ratio)},
                      {"faces", t.faces}};
  if (t.phong) {
    j["phong"] = summary_json(*t.phong);
    j["phong_ratio"] = summary_json(t.phong_ratio);
  }
  return j;
}

nlohmann::json accuracy_json(const mbi::interp::Accuracy& a) {
  return {{"position_rms", a.position_rms},
          {"position_max", a.position_max},
          {"gradient_rms", a.gradient_rms},
          {"gradient_max", a.gradient_max},
          {"size", a.size}};
}

std::string format_table(const mbi::interp::DiscontinuityTable& t) {
  std::ostringstream o;
  char line[160];
  if (t.phong) {
    std::snprintf(line, sizeof line, "%-8s %14s %14s %14s %10s %10s\n", "", "BI", "Phong",
                  "modified-BI", "BI/Phong", "BI/mod-BI");
    o << line;
    auto row = [&](const char* name, double a, double p, double b, double rp, double r) {
      std::snprintf(line, sizeof line, "%-8s %14.6g %14.6g %14.6g %10.1f %10.1f\n", name, a, p, b,
                    rp, r);
      o << line;
    };
    row("Mean", t.bi.mean, t.phong->mean, t.modified_bi.mean, t.phong_ratio.mean, t.ratio.mean);
    row("StdDev", t.bi.std, t.phong->std, t.modified_bi.std, t.phong_ratio.std, t.ratio.std);
    row("Max", t.bi.max, t.phong->max, t.modified_bi.max, t.phong_ratio.max, t.ratio.max);
    return o.str();
  }
  std::snprintf(line, sizeof line, "%-8s %14s %14s %10s\n", "", "BI", "modified-BI", "ratio");
  o << line;
  auto row = [&](const char* name, double a, double b, double r) {
    std::snprintf(line, sizeof line, "%-8s %14.6g %14.6g %10.1f\n", name, a, b, r);
    o << line;
  };
  row("Mean", t.bi.mean, t.modified_bi.mean, t.ratio.mean);
  row("StdDev", t.bi.std, t.modified_bi.std, t.ratio.std);
  row("Max", t.bi.max, t.modified_bi.max, t.ratio.max);
  return o.str();
}

}  // namespace mbi::scenes

namespace mbi::scenes {

std::string format_accuracy(const std::vector<std::pair<std::string, mbi::interp::Accuracy>>& rows) {
  std::ostringstream o;
  char line[160];
  std::snprintf(line, sizeof line, "%-12s %14s %14s %14s %14s\n", "", "pos RMS", "pos max",
                "grad RMS", "grad max");
  o << line;
  for (const auto& [name, a] : rows) {
    std::snprintf(line, sizeof line, "%-12s %14.4e %14.4e %14.4e %14.4e\n", name.c_str(),
                  a.position_rms, a.position_max, a.gradient_rms, a.gradient_max);
    o << line;
  }
  return o.str();
}

}  // namespace mbi::scenes
