#include <mbi/scenes/report.hpp>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <tuple>
#include <sstream>

namespace mbi::scenes {

nlohmann::json number_json(double x) {
  if (std::isfinite(x)) return x;
  return std::isnan(x) ? "nan" : (x > 0 ? "inf" : "-inf");
}

nlohmann::json summary_json(const mbi::interp::Summary& s) {
  return {{"mean", number_json(s.mean)}, {"std", number_json(s.std)}, {"max", number_json(s.max)}};
}

namespace {
nlohmann::json finite_summary(const mbi::interp::Summary& s, const char* key) {
  for (double v : {s.mean, s.std, s.max})
    if (!std::isfinite(v))
      throw std::domain_error(std::string("discontinuity table: ") + key + " is not finite (" +
                              std::to_string(v) + ")");
  return summary_json(s);
}
// ratio = num / den field by field; null where den is at round-off (undefined)
nlohmann::json ratio_json(const mbi::interp::Summary& r, const mbi::interp::Summary& den,
                          double roundoff, const char* key) {
  nlohmann::json j;
  for (auto [name, rv, dv] : {std::tuple{"mean", r.mean, den.mean}, {"std", r.std, den.std},
                              {"max", r.max, den.max}}) {
    if (dv <= roundoff) {
      j[name] = nullptr;
    } else {
      if (!std::isfinite(rv))
        throw std::domain_error(std::string("discontinuity table: ") + key + "." + name +
                                " is not finite");
      j[name] = rv;
    }
  }
  return j;
}
}  // namespace

double disc_roundoff(const Eigen::Ref<const Eigen::MatrixXd>& U) {
  if (U.rows() == 0) return 0.0;
  const double L = (U.colwise().maxCoeff() - U.colwise().minCoeff()).norm();
  return 1e-20 * std::pow(L, static_cast<double>(U.cols() - 1));
}

nlohmann::json disc_json(const mbi::interp::DiscontinuityTable& t, double roundoff) {
  nlohmann::json j = {{"bi", finite_summary(t.bi, "bi")},
                      {"modified_bi", finite_summary(t.modified_bi, "modified_bi")},
                      {"ratio", ratio_json(t.ratio, t.modified_bi, roundoff, "ratio")},
                      {"faces", t.faces}};
  if (t.phong) {
    j["phong"] = finite_summary(*t.phong, "phong");
    j["phong_ratio"] = ratio_json(t.phong_ratio, *t.phong, roundoff, "phong_ratio");
  }
  return j;
}

nlohmann::json accuracy_json(const mbi::interp::Accuracy& a) {
  return {{"position_rms", number_json(a.position_rms)},
          {"position_max", number_json(a.position_max)},
          {"gradient_rms", number_json(a.gradient_rms)},
          {"gradient_max", number_json(a.gradient_max)},
          {"size", number_json(a.size)}};
}

std::string format_table(const mbi::interp::DiscontinuityTable& t, double roundoff) {
  std::ostringstream o;
  char line[160];
  auto num = [](double v, double den, double level) {
    char b[32];
    if (den <= level) return std::string("-");
    std::snprintf(b, sizeof b, "%.1f", v);
    return std::string(b);
  };
  if (t.phong) {
    std::snprintf(line, sizeof line, "%-8s %14s %14s %14s %10s %10s\n", "", "BI", "Phong",
                  "modified-BI", "BI/Phong", "BI/mod-BI");
    o << line;
    auto row = [&](const char* name, double a, double p, double b, double rp, double r) {
      std::snprintf(line, sizeof line, "%-8s %14.6g %14.6g %14.6g %10s %10s\n", name, a, p, b,
                    num(rp, p, roundoff).c_str(), num(r, b, roundoff).c_str());
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
    std::snprintf(line, sizeof line, "%-8s %14.6g %14.6g %10s\n", name, a, b,
                  num(r, b, roundoff).c_str());
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
