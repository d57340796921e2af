#include <mbi/scenes/report.hpp>

#include <cstdio>
#include <sstream>

namespace mbi::scenes {

nlohmann::json summary_json(const mbi::interp::Summary& s) {
  return {{"mean", s.mean}, {"std", s.std}, {"max", s.max}};
}

nlohmann::json disc_json(const mbi::interp::DiscontinuityTable& t) {
  return {{"bi", summary_json(t.bi)},
          {"modified_bi", summary_json(t.modified_bi)},
          {"ratio", summary_json(t.ratio)},
          {"faces", t.faces}};
}

std::string format_table(const mbi::interp::DiscontinuityTable& t) {
  std::ostringstream o;
  char line[160];
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
