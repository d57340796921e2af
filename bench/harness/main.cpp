// mbi-harness: how mbi behaves inside an application, measured through the INSTALLED library
// (find_package(mbi)) with geometry and loads of its own, so that the code measured cannot shape
// the measurement. Scenarios (scenarios.hpp): an interleaved frame loop against its phases alone,
// the first solve after a precompute, every stage quiet and beside a load (loads.hpp), the
// one-shot evaluate<float> against FastEvaluator, and two caller threads at once.
//
//   mbi-harness [--out FILE.json] [--points N] [--reps R] [--only frame,first_solve,loaded,one_shot,callers]
//               [--loads quiet,thread,process,numpy-like,torch-like] [--threads N]
//
// --threads N sets the library's thread count (mbi::interp::set_threads, when the installed
// library has it). Rows are printed as they come and written as JSON ({"context", "rows"}).
#include "scenarios.hpp"

#if __has_include(<mbi/interp/threads.hpp>)
#include <mbi/interp/threads.hpp>
#define HARNESS_SET_THREADS 1
#endif

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace {

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string x; std::getline(ss, x, ',');)
    if (!x.empty()) out.push_back(x);
  return out;
}

bool wanted(const std::vector<std::string>& only, const std::string& s) {
  if (only.empty()) return true;
  for (const auto& o : only)
    if (o == s) return true;
  return false;
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') o += '\\';
    o += ch;
  }
  return o + "\"";
}

void write_json(const std::string& path, const harness::Report& r, long long points, int reps, int threads) {
  std::ofstream f(path);
  char host[256] = "?";
  gethostname(host, sizeof host);
  const std::time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%S%z", std::localtime(&now));
  f << "{\n \"context\": {\"date\": " << json_string(date) << ", \"host\": " << json_string(host)
    << ", \"library\": " << json_string(HARNESS_MBI_DIR) << ", \"points\": " << points
    << ", \"reps\": " << reps << ", \"threads\": " << threads << ", \"cores\": " << sysconf(_SC_NPROCESSORS_ONLN)
    << "},\n \"rows\": [\n";
  for (size_t i = 0; i < r.rows.size(); ++i) {
    const harness::Row& w = r.rows[i];
    f << "  {\"scenario\": " << json_string(w.scenario) << ", \"name\": " << json_string(w.name)
      << ", \"load\": " << json_string(w.load) << ", \"ms\": " << w.ms << ", \"mean_ms\": " << w.mean_ms << ", \"samples\": " << w.samples
      << ", \"note\": " << json_string(w.note) << "}" << (i + 1 < r.rows.size() ? "," : "") << "\n";
  }
  f << " ]\n}\n";
}

}  // namespace

int main(int argc, char** argv) {
  std::string out, only_s, loads_s = "quiet,thread,process,numpy-like,torch-like";
  long long points = 1000000;
  int reps = 1, threads = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "mbi-harness: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--out") out = next();
    else if (a == "--points") points = std::atoll(next().c_str());
    else if (a == "--reps") reps = std::atoi(next().c_str());
    else if (a == "--only") only_s = next();
    else if (a == "--loads") loads_s = next();
    else if (a == "--threads") threads = std::atoi(next().c_str());
    else {
      std::fprintf(stderr, "usage: mbi-harness [--out F] [--points N] [--reps R] [--only LIST] [--loads LIST] [--threads N]\n");
      return 2;
    }
  }
#ifdef HARNESS_SET_THREADS
  if (threads > 0) mbi::interp::set_threads(threads);
#else
  if (threads > 0) std::fprintf(stderr, "mbi-harness: this library has no set_threads; --threads ignored\n");
#endif
  const std::vector<std::string> only = split(only_s);
  std::vector<harness::Load> loads;
  for (const auto& n : split(loads_s))
    for (harness::Load l : {harness::Load::None, harness::Load::Thread, harness::Load::Process,
                            harness::Load::Blas, harness::Load::OpenMP})
      if (n == harness::name(l) && harness::available(l)) loads.push_back(l);
  if (loads.empty() || loads[0] != harness::Load::None) loads.insert(loads.begin(), harness::Load::None);

  std::printf("mbi-harness: library %s, %lld points, %d rounds\n", HARNESS_MBI_DIR, points, reps);
  harness::Context c(points, reps);
  harness::Report r;
  if (wanted(only, "one_shot")) harness::one_shot(c, r);
  if (wanted(only, "frame")) harness::frame_loop(c, r);
  if (wanted(only, "first_solve")) harness::first_solve(c, r);
  if (wanted(only, "callers")) harness::callers(c, r);
  if (wanted(only, "loaded")) harness::loaded(c, r, loads);
  if (!out.empty()) write_json(out, r, points, reps, threads);
  return 0;
}
