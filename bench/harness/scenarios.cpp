// The harness's scenarios (see scenarios.hpp).
#include "scenarios.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <thread>

namespace harness {
namespace {

using Clock = std::chrono::steady_clock;

volatile double g_sink;  // keeps the arithmetic of app_work and sweep_cache

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// About `ms` of the application's own serial work on the calling thread (arithmetic), between
// two calls into the library: what a frame does besides them (when idle pool threads spin).
void app_work(double ms) {
  const auto t0 = Clock::now();
  double x = 1.0;
  while (ms_since(t0) < ms)
    for (int i = 0; i < 1000; ++i) x = x * 1.0000001 + 1e-9;
  g_sink = x;
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / v.size();
}

// Times f up to n times, each after `gap_ms` of app_work, stopping after budget_ms once 3
// samples are in.
std::vector<double> times(int n, const std::function<void()>& f, double gap_ms = 0, double budget_ms = 4000) {
  std::vector<double> t;
  const auto start = Clock::now();
  for (int i = 0; i < n; ++i) {
    if (gap_ms > 0) app_work(gap_ms);
    const auto t0 = Clock::now();
    f();
    t.push_back(ms_since(t0));
    if (t.size() >= 3 && ms_since(start) > budget_ms) break;
  }
  return t;
}

// Reads a buffer larger than the last-level cache: what a frame's other phases leave behind.
void sweep_cache() {
  static std::vector<double> big(8 << 20, 1.0);  // 64 MB
  double s = 0;
  for (size_t i = 0; i < big.size(); i += 8) s += big[i];
  g_sink = s;
}

std::string ratio(double a, double b) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2fx", b > 0 ? a / b : 0.0);
  return buf;
}

int process_threads() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  return -1;
}

}  // namespace

void Report::add(Row r) {
  char m[32] = "";
  if (r.mean_ms > 0) std::snprintf(m, sizeof m, "mean %9.3f", r.mean_ms);
  std::printf("%-12s %-40s %-11s %9.3f ms %-14s n=%-3d %s\n", r.scenario.c_str(), r.name.c_str(), r.load.c_str(),
              r.ms, m, r.samples, r.note.c_str());
  std::fflush(stdout);
  rows.push_back(std::move(r));
}

Context::Context(long long points, int reps_) : reps(std::max(1, reps_)) {
  c448 = box(7, 7, 6);
  c1331 = box(10, 10, 10);
  X448 = pose(c448, 1.0);
  X1331 = pose(c1331, 1.0);
  emb = interp::embed(c448.U, c448.T, cloud(c448, points));
  mbi448 = std::make_unique<interp::ModifiedBI>(c448.U, c448.T);
  mbi1331 = std::make_unique<interp::ModifiedBI>(c1331.U, c1331.T);
  fast = std::make_unique<interp::FastEvaluator>(emb);
}

void frame_loop(Context& c, Report& r) {
  const int N = 30;
  std::vector<Eigen::MatrixXd> X(N);
  for (int f = 0; f < N; ++f) X[f] = pose(c.c448, 0.5 + 0.5 * f / N);
  const interp::ModifiedBI& s = *c.mbi448;
  interp::RowMatrixXf pos;
  interp::VertexMatrices M = s.solve(X[0]);
  interp::BezierPoints B = s.bezier(X[0], M);
  c.fast->evaluate(B, pos);
  std::vector<double> solve, bez, eval, solve_c, bez_c, eval_c, frame, f_solve, f_bez, f_eval;
  auto timed = [](std::vector<double>& v, const std::function<void()>& f, bool cold) {
    if (cold) sweep_cache();
    const auto t0 = Clock::now();
    f();
    v.push_back(ms_since(t0));
  };
  for (int round = 0; round < c.reps; ++round) {
    for (bool cold : {false, true}) {
      for (int f = 0; f < N; ++f) timed(cold ? solve_c : solve, [&] { M = s.solve(X[f]); }, cold);
      for (int f = 0; f < N; ++f) timed(cold ? bez_c : bez, [&] { B = s.bezier(X[f], M); }, cold);
      for (int f = 0; f < N; ++f) timed(cold ? eval_c : eval, [&] { c.fast->evaluate(B, pos); }, cold);
    }
    for (int f = 0; f < N; ++f) {
      const auto t0 = Clock::now();
      M = s.solve(X[f]);
      const auto t1 = Clock::now();
      B = s.bezier(X[f], M);
      const auto t2 = Clock::now();
      c.fast->evaluate(B, pos);
      const auto t3 = Clock::now();
      auto d = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
      f_solve.push_back(d(t0, t1));
      f_bez.push_back(d(t1, t2));
      f_eval.push_back(d(t2, t3));
      frame.push_back(d(t0, t3));
    }
  }
  const double alone = median(solve) + median(bez) + median(eval);
  const double cold = median(solve_c) + median(bez_c) + median(eval_c);
  const int n = static_cast<int>(frame.size());
  r.add({"frame", "solve alone (448)", "quiet", median(solve), n, ""});
  r.add({"frame", "bezier alone", "quiet", median(bez), n, ""});
  r.add({"frame", "evaluate alone (fast, all threads)", "quiet", median(eval), n, ""});
  r.add({"frame", "sum of the phases alone", "quiet", alone, n, ""});
  r.add({"frame", "solve alone, cache swept", "quiet", median(solve_c), n, ""});
  r.add({"frame", "bezier alone, cache swept", "quiet", median(bez_c), n, ""});
  r.add({"frame", "evaluate alone, cache swept", "quiet", median(eval_c), n, ""});
  r.add({"frame", "sum of the phases alone, cache swept", "quiet", cold, n, ratio(cold, alone) + " of warm"});
  r.add({"frame", "interleaved: solve", "quiet", median(f_solve), n, ratio(median(f_solve), median(solve)) + " of alone"});
  r.add({"frame", "interleaved: bezier", "quiet", median(f_bez), n, ratio(median(f_bez), median(bez)) + " of alone"});
  r.add({"frame", "interleaved: evaluate", "quiet", median(f_eval), n, ratio(median(f_eval), median(eval)) + " of alone"});
  r.add({"frame", "interleaved frame", "quiet", median(frame), n, ratio(median(frame), alone) + " of the sum alone"});
}

void first_solve(Context& c, Report& r) {
  interp::RowMatrixXf pos;
  const interp::BezierPoints B = c.mbi448->bezier(c.X448, c.mbi448->solve(c.X448));
  std::vector<double> pre, first, after, ratios;
  for (int round = 0; round < 3 * c.reps; ++round) {
    for (int i = 0; i < 3; ++i) c.fast->evaluate(B, pos);
    auto t0 = Clock::now();
    interp::ModifiedBI s(c.c1331.U, c.c1331.T);
    pre.push_back(ms_since(t0));
    t0 = Clock::now();
    interp::VertexMatrices M = s.solve(c.X1331);
    first.push_back(ms_since(t0));
    const double rest = median(times(20, [&] { M = s.solve(c.X1331); }));
    after.push_back(rest);
    ratios.push_back(first.back() / rest);
  }
  const int n = static_cast<int>(first.size());
  r.add({"first_solve", "precompute 1331", "quiet", median(pre), n, ""});
  r.add({"first_solve", "first solve after it", "quiet", median(first), n,
         ratio(median(ratios), 1.0) + " (worst " + ratio(*std::max_element(ratios.begin(), ratios.end()), 1.0) + ")"});
  r.add({"first_solve", "solves after that", "quiet", median(after), n, ""});
}

void loaded(Context& c, Report& r, const std::vector<Load>& loads) {
  interp::RowMatrixXf pos;
  Eigen::MatrixXf posf;
  Eigen::MatrixXd posd;
  interp::VertexMatrices M = c.mbi448->solve(c.X448);
  interp::BezierPoints B = c.mbi448->bezier(c.X448, M);
  const Eigen::MatrixXd P = cloud(c.c448, c.emb.size());
  struct Stage {
    std::string name;
    int n;
    std::function<void()> run;
  };
  const std::vector<Stage> stages = {
      {"precompute 448", 5, [&] { interp::ModifiedBI s(c.c448.U, c.c448.T); }},
      {"precompute 1331", 5, [&] { interp::ModifiedBI s(c.c1331.U, c.c1331.T); }},
      {"solve 448 (dense operator)", 40, [&] { M = c.mbi448->solve(c.X448); }},
      {"solve 1331 (sparse sweeps)", 40, [&] { c.mbi1331->solve(c.X1331); }},
      {"bezier 448", 40, [&] { B = c.mbi448->bezier(c.X448, M); }},
      {"evaluate 1M (fast, all threads)", 30, [&] { c.fast->evaluate(B, pos); }},
      {"evaluate<float> 1M (one-shot)", 10, [&] { interp::evaluate<float>(B, c.emb, posf); }},
      {"evaluate<double> 1M", 10, [&] { interp::evaluate<double>(B, c.emb, posd); }},
      {"embed 1M", 3, [&] { interp::embed(c.c448.U, c.c448.T, P); }},
      {"frame 448 / 1M", 30, [&] {
         M = c.mbi448->solve(c.X448);
         B = c.mbi448->bezier(c.X448, M);
         c.fast->evaluate(B, pos);
       }},
  };
  for (const Stage& s : stages) s.run();  // first touch of every output
  std::vector<std::vector<std::vector<double>>> t(loads.size(), std::vector<std::vector<double>>(stages.size()));
  for (int round = 0; round < c.reps; ++round)
    for (size_t l = 0; l < loads.size(); ++l) {
      LoadGuard g(loads[l]);
      for (size_t s = 0; s < stages.size(); ++s) {
        const std::vector<double> v = times(stages[s].n, stages[s].run, 1.0);
        t[l][s].insert(t[l][s].end(), v.begin(), v.end());
      }
    }
  for (size_t s = 0; s < stages.size(); ++s)
    for (size_t l = 0; l < loads.size(); ++l) {
      const double q = mean(t[0][s]), m = mean(t[l][s]);
      r.add({"loaded", stages[s].name, name(loads[l]), median(t[l][s]), static_cast<int>(t[l][s].size()),
             l == 0 ? "" : ratio(m, q) + " of quiet (means)", m});
    }
}

void one_shot(Context& c, Report& r) {
  const interp::BezierPoints B = c.mbi448->bezier(c.X448, c.mbi448->solve(c.X448));
  Eigen::MatrixXf posf;
  Eigen::MatrixXd posd;
  interp::RowMatrixXf pos;
  // the plain loop of a BI user: 4 vertex indices and 4 weights a point, double, 1 thread
  const long long p = c.emb.size();
  std::vector<int> vert(4 * p);
  std::vector<double> w(4 * p), out(3 * p);
  for (long long i = 0; i < p; ++i)
    for (int k = 0; k < 4; ++k) {
      vert[4 * i + k] = c.c448.T(c.emb.element(i), k);
      w[4 * i + k] = c.emb.bary(i, k);
    }
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> X = c.X448;
  auto plain = [&] {
    for (long long i = 0; i < p; ++i) {
      double d0 = 0, d1 = 0, d2 = 0;
      for (int k = 0; k < 4; ++k) {
        const double* x = X.data() + 3 * vert[4 * i + k];
        d0 += w[4 * i + k] * x[0];
        d1 += w[4 * i + k] * x[1];
        d2 += w[4 * i + k] * x[2];
      }
      out[3 * i] = d0, out[3 * i + 1] = d1, out[3 * i + 2] = d2;
    }
  };
  std::vector<double> tf, tfast, td, tp;
  interp::evaluate<float>(B, c.emb, posf);
  interp::evaluate<double>(B, c.emb, posd);
  c.fast->evaluate(B, pos);
  plain();
  for (int round = 0; round < c.reps; ++round) {
    for (double v : times(20, [&] { interp::evaluate<float>(B, c.emb, posf); })) tf.push_back(v);
    for (double v : times(20, [&] { c.fast->evaluate(B, pos); })) tfast.push_back(v);
    for (double v : times(20, [&] { interp::evaluate<double>(B, c.emb, posd); })) td.push_back(v);
    for (double v : times(20, plain)) tp.push_back(v);
  }
  const double fast = median(tfast);
  r.add({"one_shot", "FastEvaluator (all threads)", "quiet", fast, static_cast<int>(tfast.size()), ""});
  r.add({"one_shot", "evaluate<float> (all threads)", "quiet", median(tf), static_cast<int>(tf.size()),
         ratio(median(tf), fast) + " of FastEvaluator"});
  r.add({"one_shot", "evaluate<double> (all threads)", "quiet", median(td), static_cast<int>(td.size()),
         ratio(median(td), fast) + " of FastEvaluator"});
  r.add({"one_shot", "plain double BI loop (1 thread)", "quiet", median(tp), static_cast<int>(tp.size()),
         ratio(median(tf), median(tp)) + " = evaluate<float> / it"});
}

void callers(Context& c, Report& r) {
  const int F = 30;
  // each caller: its own precompute and evaluator (two objects, as two Python threads hold)
  struct Caller {
    std::unique_ptr<interp::ModifiedBI> s;
    std::unique_ptr<interp::FastEvaluator> fast;
    std::vector<double> frames;
  };
  Caller a, b;
  for (Caller* k : {&a, &b}) {
    k->s = std::make_unique<interp::ModifiedBI>(c.c448.U, c.c448.T);
    k->fast = std::make_unique<interp::FastEvaluator>(c.emb);
  }
  auto run = [&](Caller& k) {
    interp::RowMatrixXf pos;
    for (int f = 0; f < F * c.reps; ++f) {
      const auto t0 = Clock::now();
      const interp::VertexMatrices M = k.s->solve(c.X448);
      k.fast->evaluate(k.s->bezier(c.X448, M), pos);
      k.frames.push_back(ms_since(t0));
    }
  };
  auto with_sampler = [&](const std::function<void()>& f) {
    std::atomic<bool> stop{false};
    std::atomic<int> most{0};
    std::thread sampler([&] {
      while (!stop) {
        most = std::max(most.load(), process_threads());
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
    });
    f();
    stop = true;
    sampler.join();
    return most.load();
  };
  const int base = process_threads();  // main thread and whatever the library keeps
  const int alone = with_sampler([&] { run(a); });
  const double t1 = median(a.frames);
  a.frames.clear();
  const int both = with_sampler([&] {
    std::thread ta([&] { run(a); }), tb([&] { run(b); });
    ta.join();
    tb.join();
  });
  const double t2 = std::max(median(a.frames), median(b.frames));
  r.add({"callers", "one caller: frame", "quiet", t1, F * c.reps,
         "threads of the process: " + std::to_string(alone - 1) + " (idle: " + std::to_string(base) + ")"});
  r.add({"callers", "two callers at once: frame (slower)", "quiet", t2, F * c.reps,
         ratio(t2, t1) + " of one caller; threads of the process: " + std::to_string(both - 1)});
}

}  // namespace harness
