// Control trajectories (Trajectory): a point cache read a frame at a time, or a list of files
// (a .pvd, a printf pattern, a glob) read one by one by read_positions.
#include "io_common.hpp"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <cstdio>

namespace mbi::io {

using detail::fail;
using std::filesystem::path;

namespace {

bool has_glob_chars(const std::string& s) { return s.find_first_of("*?[") != std::string::npos; }

// The printf pattern's parts: prefix, digits (0: "%d"), suffix; nullopt when `spec` has no
// conversion (%d, %Nd) at all: "100%.obj" is a plain name. In a pattern "%%" is a percent sign
// and anything else after '%' but d / 0Nd is refused.
struct Pattern {
  std::string prefix, suffix;
  int digits = 0;
  path name(int k) const {
    char num[32];
    std::snprintf(num, sizeof num, "%0*d", digits, k);
    return prefix + num + suffix;
  }
};
std::optional<Pattern> printf_pattern(const std::string& spec) {
  if (!is_numbered_name(spec)) return std::nullopt;
  Pattern p;
  std::string* part = &p.prefix;
  bool found = false;
  for (std::size_t i = 0; i < spec.size(); ++i) {
    if (spec[i] != '%') {
      *part += spec[i];
      continue;
    }
    if (i + 1 < spec.size() && spec[i + 1] == '%') {
      *part += '%';
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < spec.size() && std::isdigit(static_cast<unsigned char>(spec[j]))) ++j;
    const std::string width = spec.substr(i + 1, j - i - 1);
    if (found || j >= spec.size() || spec[j] != 'd' || (!width.empty() && (width[0] != '0' || width.size() > 3)))
      fail(spec, 0, "a numbered name takes one %d or %0Nd (e.g. x_%04d.vtk; %% for a percent sign)");
    p.digits = width.empty() ? 0 : std::stoi(width);
    if (p.digits > 12) fail(spec, 0, "at most 12 digits (%012d)");
    found = true;
    part = &p.suffix;
    i = j;
  }
  if (!found) fail(spec, 0, "a numbered name takes one %d or %0Nd (e.g. x_%04d.vtk; %% for a percent sign)");
  if (p.suffix.find('/') != std::string::npos)
    fail(spec, 0, "the number must be in the file name, not in a folder name");
  return p;
}

bool is_file(const path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec);
}

// What a frame named `p` is, when it is not a regular file.
std::string not_a_file(const path& p) {
  std::error_code ec;
  if (std::filesystem::is_directory(p, ec)) return "is a folder, not a file of positions";
  return std::filesystem::exists(p, ec) ? "is not a regular file" : "does not exist";
}

// Names with runs of digits compared as numbers: x_2 before x_10.
bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])), db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::size_t is = i, js = j;  // without leading zeros
      while (is + 1 < ie && a[is] == '0') ++is;
      while (js + 1 < je && b[js] == '0') ++js;
      if (ie - is != je - js) return ie - is < je - js;
      const int c = a.compare(is, ie - is, b, js, je - js);
      if (c != 0) return c < 0;
      if (ie - i != je - j) return ie - i > je - j;  // 007 before 7: more zeros first
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

std::vector<path> glob_files(const std::string& spec) {
  glob_t g{};
  const int rc = ::glob(spec.c_str(), GLOB_ERR, nullptr, &g);
  std::vector<std::string> names;
  if (rc == 0)
    for (std::size_t i = 0; i < g.gl_pathc; ++i) names.emplace_back(g.gl_pathv[i]);
  ::globfree(&g);
  if (rc == GLOB_NOMATCH || (rc == 0 && names.empty())) fail(spec, 0, "no file matches");
  if (rc != 0) fail(spec, 0, "cannot list the files that match (a folder cannot be read)");
  std::sort(names.begin(), names.end(), natural_less);
  return {names.begin(), names.end()};
}

}  // namespace

bool is_numbered_name(const std::string& name) {
  for (std::size_t i = 0; i < name.size(); ++i) {
    if (name[i] != '%') continue;
    if (i + 1 < name.size() && name[i + 1] == '%') {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < name.size() && std::isdigit(static_cast<unsigned char>(name[j]))) ++j;
    if (j < name.size() && name[j] == 'd') return true;
  }
  return false;
}

path numbered_file(const std::string& pattern, int k) {
  const std::optional<Pattern> p = printf_pattern(pattern);
  if (!p) fail(pattern, 0, "a numbered name takes one %d or %0Nd (e.g. out_%04d.obj)");
  if (k < 0) fail(pattern, 0, "negative frame number " + std::to_string(k));
  return p->name(k);
}

struct Trajectory::Impl {
  std::string spec, displacement;
  std::unique_ptr<PointCacheReader> cache;
  std::vector<path> files;   // one a frame (when not a cache)
  path collection;           // the .pvd, if any
  std::vector<double> times;
  std::optional<std::pair<float, float>> pc2;

  void open_files(std::vector<path> f) {
    for (std::size_t k = 0; k < f.size(); ++k)
      if (!is_file(f[k])) fail(f[k], 0, "frame " + std::to_string(k) + " of " + spec + ": " + not_a_file(f[k]));
    for (const path& p : f) {
      const FileFormat* fmt = file_format(p);
      if (fmt && fmt->kind != FileKind::control && fmt->kind != FileKind::points)
        fail(p, 0, std::string("a frame must be a file of positions (.node, .vtk, .vtu, .msh or text), not a ") + fmt->name);
    }
    files = std::move(f);
  }
  void open_pvd(const path& pvd) {
    collection = pvd;
    std::vector<path> f;
    const std::vector<PvdEntry> entries = read_pvd(pvd);
    for (std::size_t k = 0; k < entries.size(); ++k) {
      if (!is_file(entries[k].file))
        fail(pvd, entries[k].line, "frame " + std::to_string(k) + ": " + entries[k].file.string() +
                                       (std::filesystem::exists(entries[k].file) ? " is not a regular file" : " does not exist"));
      f.push_back(entries[k].file);
      times.push_back(entries[k].time);
    }
    open_files(std::move(f));
  }
  void open_pattern(const Pattern& p) {
    int k = is_file(p.name(0)) ? 0 : 1;
    if (!is_file(p.name(k)))
      fail(spec, 0, "no frame file: neither " + p.name(0).string() + " nor " + p.name(1).string() + " exists");
    std::vector<path> f;
    for (; k < kMaxCount && is_file(p.name(k)); ++k) f.push_back(p.name(k));
    open_files(std::move(f));
  }
};

Trajectory::Trajectory(const std::string& spec, const std::string& displacement) : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.spec = spec;
  I.displacement = displacement;
  const std::string ext = lower_extension(spec);
  if (const std::optional<Pattern> p = printf_pattern(spec)) {
    I.open_pattern(*p);
  } else if (has_glob_chars(path(spec).filename().string())) {
    I.open_files(glob_files(spec));
  } else if (ext == ".pc2" || ext == ".mdd") {
    I.cache = std::make_unique<PointCacheReader>(spec);
    if (ext == ".pc2") I.pc2 = std::pair{I.cache->start_frame(), I.cache->sample_rate()};
  } else if (ext == ".pvd") {
    I.open_pvd(spec);
  } else {
    if (!std::filesystem::exists(spec)) detail::require_regular_file(spec);  // names the missing file
    I.open_files({path(spec)});
  }
  if (I.cache && !displacement.empty())
    fail(spec, 0, "no point field '" + displacement + "': a point cache holds positions only (displacement fields are read from .vtu and .vtk frames)");
}

Trajectory::~Trajectory() = default;
Trajectory::Trajectory(Trajectory&&) noexcept = default;
Trajectory& Trajectory::operator=(Trajectory&&) noexcept = default;

bool Trajectory::names_trajectory(const std::string& spec) {
  const std::string ext = lower_extension(spec);
  return ext == ".pc2" || ext == ".mdd" || ext == ".pvd" || is_numbered_name(spec) ||
         has_glob_chars(path(spec).filename().string());
}

int Trajectory::frames() const {
  return impl_->cache ? impl_->cache->frames() : static_cast<int>(impl_->files.size());
}

Eigen::MatrixXd Trajectory::read(int k) {
  const Impl& I = *impl_;
  if (I.cache) return I.cache->frame(k);
  try {
    return read_positions(I.files.at(static_cast<std::size_t>(k)), I.displacement);
  } catch (const Error& e) {
    throw Error("frame " + std::to_string(k) + ": " + e.what());
  }
}

path Trajectory::file(int k) const { return impl_->cache ? path() : impl_->files.at(static_cast<std::size_t>(k)); }

std::string Trajectory::where(int k) const {
  const Impl& I = *impl_;
  if (I.cache) return I.spec + ": frame " + std::to_string(k);
  return "frame " + std::to_string(k) + ": " + I.files.at(static_cast<std::size_t>(k)).string();
}

const std::vector<double>& Trajectory::times() const {
  Impl& I = *impl_;
  if (I.cache && I.cache->has_times() && I.times.empty())
    for (float t : I.cache->times()) I.times.push_back(t);
  return I.times;
}

bool Trajectory::has_times() const { return !impl_->times.empty() || (impl_->cache && impl_->cache->has_times()); }

const std::string& Trajectory::spec() const { return impl_->spec; }

std::optional<std::pair<float, float>> Trajectory::pc2_timing() const { return impl_->pc2; }

std::vector<path> Trajectory::files() const {
  if (impl_->cache) return {impl_->cache->file()};
  std::vector<path> f = impl_->files;
  if (!impl_->collection.empty()) f.push_back(impl_->collection);
  return f;
}

}  // namespace mbi::io
