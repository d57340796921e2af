// VTK XML unstructured grids (.vtu): read, in every encoding of the format (see read_vtu_mesh).
// The XML is parsed by pugixml; raw appended data, which is not XML, is cut off first and read
// from the bytes. A DataArray's data, binary or not, is decoded here (base64, zlib).
#include "control.hpp"

#include <pugixml.hpp>
#include <zlib.h>

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <new>
#include <optional>

namespace mbi::io {
namespace {

using detail::fail;
using std::filesystem::path;

// The bytes of an encoded DataArray, handed out in order: raw bytes, or base64 text decoded on
// the way. Base64 streams may follow each other (VTK encodes a compressed array's header and
// its blocks separately): padding ends one and the next begins.
class DataBytes {
 public:
  DataBytes(std::string_view s, bool base64) : s_(s), base64_(base64) {}

  // Appends the next n bytes to out; false when the data ends first.
  bool take(std::size_t n, std::string& out) {
    if (!base64_) {
      if (s_.size() - pos_ < n) return false;
      out.append(s_.data() + pos_, n);
      pos_ += n;
      return true;
    }
    while (pending_.size() < n) {
      if (!quantum()) return false;
    }
    out.append(pending_, 0, n);
    pending_.erase(0, n);
    return true;
  }
  // At most this many bytes are left (to check counts before allocating for them).
  std::size_t bound() const { return base64_ ? (s_.size() - pos_) / 4 * 3 + 3 + pending_.size() : s_.size() - pos_; }
  bool bad() const { return bad_; }

 private:
  static int value(char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  }
  // Decodes the next 4 characters (blanks skipped) into pending_; false at the end or on a
  // character that is not base64 (then bad()).
  bool quantum() {
    int v[4], got = 0, pad = 0;
    while (got < 4 && pos_ < s_.size()) {
      const char c = s_[pos_++];
      if (c == ' ' || c == '\n' || c == '\r' || c == '\t') continue;
      if (c == '=' && got >= 2) {
        v[got++] = 0;
        ++pad;
        continue;
      }
      const int x = pad > 0 ? -1 : value(c);
      if (x < 0) return !(bad_ = true);
      v[got++] = x;
    }
    if (got < 4) return false;
    const std::uint32_t w = (std::uint32_t(v[0]) << 18) | (std::uint32_t(v[1]) << 12) | (std::uint32_t(v[2]) << 6) | std::uint32_t(v[3]);
    const char b[3] = {char(w >> 16), char(w >> 8), char(w)};
    pending_.append(b, 3 - static_cast<std::size_t>(pad));
    return true;
  }
  std::string_view s_;
  bool base64_;
  std::size_t pos_ = 0;
  std::string pending_;
  bool bad_ = false;
};

// A DataArray's element type: its size and how a value becomes a double.
struct Scalar {
  std::size_t size = 0;
  bool real = false, is_signed = false;
};
std::optional<Scalar> scalar_of(std::string_view t) {
  if (t == "Float32") return Scalar{4, true, true};
  if (t == "Float64") return Scalar{8, true, true};
  if (t == "Int8") return Scalar{1, false, true};
  if (t == "UInt8") return Scalar{1, false, false};
  if (t == "Int16") return Scalar{2, false, true};
  if (t == "UInt16") return Scalar{2, false, false};
  if (t == "Int32") return Scalar{4, false, true};
  if (t == "UInt32") return Scalar{4, false, false};
  if (t == "Int64") return Scalar{8, false, true};
  if (t == "UInt64") return Scalar{8, false, false};
  return std::nullopt;
}

double value_at(const char* p, const Scalar& s, bool swap) {
  using detail::load_bytes;
  if (s.real) return s.size == 4 ? static_cast<double>(load_bytes<float>(p, swap)) : load_bytes<double>(p, swap);
  switch (s.size) {
    case 1: return s.is_signed ? double(load_bytes<std::int8_t>(p, swap)) : double(load_bytes<std::uint8_t>(p, swap));
    case 2: return s.is_signed ? double(load_bytes<std::int16_t>(p, swap)) : double(load_bytes<std::uint16_t>(p, swap));
    case 4: return s.is_signed ? double(load_bytes<std::int32_t>(p, swap)) : double(load_bytes<std::uint32_t>(p, swap));
    default: return s.is_signed ? double(load_bytes<std::int64_t>(p, swap)) : double(load_bytes<std::uint64_t>(p, swap));
  }
}

class VtuReader {
 public:
  VtuReader(std::string_view data, const path& file) : file_(file), lines_(data) { parse(data); }

  // Points, n x 3.
  Eigen::MatrixXd points() {
    const pugi::xml_node da = piece_.child("Points").child("DataArray");
    if (!da) fail(file_, line(piece_), "Piece has no Points DataArray");
    if (da.attribute("NumberOfComponents").as_int(1) != 3)
      fail(file_, line(da), "Points: NumberOfComponents must be 3");
    const std::vector<double> v = values(da, 3 * count(piece_, "NumberOfPoints"), "Points");
    Eigen::MatrixXd P(static_cast<Eigen::Index>(v.size() / 3), 3);
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (!std::isfinite(v[i]) || std::abs(v[i]) > kMaxCoordinate)
        fail(file_, line(da), "Points: point " + std::to_string(i / 3) + " coordinate " + std::to_string(i % 3) +
                                  ": non-finite or larger in magnitude than 1e300");
      P(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = v[i];
    }
    return P;
  }

  // Every DataArray of PointData, n tuples each.
  std::vector<PointField> fields(Eigen::Index n) {
    std::vector<PointField> out;
    for (const pugi::xml_node& da : piece_.child("PointData").children("DataArray")) {
      const std::string name = da.attribute("Name").as_string();
      const int comps = da.attribute("NumberOfComponents").as_int(1);
      if (comps < 1 || comps > (1 << 20)) fail(file_, line(da), "PointData " + name + ": NumberOfComponents " + std::to_string(comps));
      const std::vector<double> v = values(da, comps * static_cast<long long>(n), "PointData " + name);
      PointField f{name, Eigen::MatrixXd(n, comps)};
      for (std::size_t i = 0; i < v.size(); ++i) f.values(static_cast<Eigen::Index>(i) / comps, static_cast<Eigen::Index>(i) % comps) = v[i];
      out.push_back(std::move(f));
    }
    return out;
  }

  // The cells: connectivity, offsets (the end of each cell) and types.
  std::vector<detail::VtkCell> cells(Eigen::Index points) {
    const pugi::xml_node c = piece_.child("Cells");
    if (!c) fail(file_, line(piece_), "Piece has no Cells");
    const long long m = count(piece_, "NumberOfCells");
    const std::vector<long long> types = integers(array(c, "types"), m, "types");
    const pugi::xml_node off = array(c, "offsets");
    const std::vector<long long> offsets = integers(off, m, "offsets");
    for (std::size_t e = 0; e < offsets.size(); ++e)
      if (offsets[e] < (e == 0 ? 0 : offsets[e - 1]) || offsets[e] > kMaxCount)
        fail(file_, line(off), "offsets: cell " + std::to_string(e) + ": offset " + std::to_string(offsets[e]) +
                                   " out of order or out of range");
    const pugi::xml_node conn = array(c, "connectivity");
    const std::vector<long long> nodes = integers(conn, m > 0 ? offsets.back() : 0, "connectivity");
    std::vector<detail::VtkCell> cells(static_cast<std::size_t>(m));
    long long at = 0;
    for (std::size_t e = 0; e < cells.size(); ++e) {
      cells[e].type = static_cast<int>(types[e]);
      for (; at < offsets[e]; ++at) {
        const long long v = nodes[static_cast<std::size_t>(at)];
        if (v < 0 || v >= points)
          fail(file_, line(conn), "cell " + std::to_string(e) + ": point index " + std::to_string(v) +
                                      " out of range [0, " + std::to_string(points) + ")");
        cells[e].nodes.push_back(v);
      }
    }
    return cells;
  }

 private:
  void parse(std::string_view data);
  void header();
  std::vector<double> values(const pugi::xml_node& da, long long count, const std::string& what);
  std::string binary(DataBytes& in, std::size_t bytes, const pugi::xml_node& da, const std::string& what);
  std::vector<double> ascii(const pugi::xml_node& da, long long count, const std::string& what);

  int line(const pugi::xml_node& n) {
    const std::ptrdiff_t at = n.offset_debug();
    return at < 0 ? 0 : lines_.line_of(static_cast<std::size_t>(at));
  }
  long long count(const pugi::xml_node& n, const char* attr) {
    const pugi::xml_attribute a = n.attribute(attr);
    if (!a) fail(file_, line(n), std::string(n.name()) + " has no " + attr);
    return detail::to_int(a.value(), file_, line(n), attr, 0, kMaxCount);
  }
  pugi::xml_node array(const pugi::xml_node& parent, const char* name) {
    const pugi::xml_node da = parent.find_child_by_attribute("DataArray", "Name", name);
    if (!da) fail(file_, line(parent), std::string(parent.name()) + " has no DataArray Name=\"" + name + "\"");
    return da;
  }
  std::vector<long long> integers(const pugi::xml_node& da, long long count, const std::string& what) {
    const std::vector<double> v = values(da, count, what);
    std::vector<long long> out(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (v[i] != std::floor(v[i]) || std::abs(v[i]) > 9e15)
        fail(file_, line(da), what + ": value " + std::to_string(i) + " is not an integer");
      out[i] = static_cast<long long>(v[i]);
    }
    return out;
  }

  const path& file_;
  detail::LineCounter lines_;
  pugi::xml_document doc_;
  pugi::xml_node piece_;
  std::string_view appended_;  // after the '_' of AppendedData
  bool appended_raw_ = false;
  bool swap_ = false;
  std::size_t header_bytes_ = 4;
  bool zlib_ = false;
};

void VtuReader::parse(std::string_view data) {
  // Raw appended data is binary, not XML: the XML parsed ends at its '_', closed by hand.
  std::string xml;
  const std::size_t a = data.find("<AppendedData");
  if (a != std::string_view::npos) {
    const std::size_t gt = data.find('>', a);
    const std::size_t us = gt == std::string_view::npos ? gt : data.find('_', gt);
    if (us == std::string_view::npos) fail(file_, lines_.line_of(a), "AppendedData without its '_' marker");
    const std::size_t end = data.rfind("</AppendedData>");
    appended_ = data.substr(us + 1, (end == std::string_view::npos || end < us ? data.size() : end) - us - 1);
    xml.assign(data.substr(0, us));
    xml += "</AppendedData></VTKFile>";
  } else {
    xml.assign(data);
  }
  const pugi::xml_parse_result r = doc_.load_buffer(xml.data(), xml.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!r) fail(file_, lines_.line_of(static_cast<std::size_t>(std::max<std::ptrdiff_t>(r.offset, 0))),
               std::string("not valid XML: ") + r.description());
  header();
}

void VtuReader::header() {
  const pugi::xml_node root = doc_.child("VTKFile");
  if (!root) fail(file_, 0, "not a VTK XML file (no VTKFile element)");
  const std::string type = root.attribute("type").value();
  if (type != "UnstructuredGrid")
    fail(file_, line(root), "VTKFile of type '" + type.substr(0, 40) + "' (only UnstructuredGrid, a .vtu, is read)");
  const std::string order = root.attribute("byte_order").as_string("LittleEndian");
  if (order != "LittleEndian" && order != "BigEndian") fail(file_, line(root), "byte_order '" + order.substr(0, 40) + "'");
  swap_ = (order == "BigEndian") != (std::endian::native == std::endian::big);
  const std::string ht = root.attribute("header_type").as_string("UInt32");
  if (ht != "UInt32" && ht != "UInt64") fail(file_, line(root), "header_type '" + ht.substr(0, 40) + "' (UInt32 or UInt64)");
  header_bytes_ = ht == "UInt64" ? 8 : 4;
  const std::string comp = root.attribute("compressor").value();
  if (!comp.empty() && comp != "vtkZLibDataCompressor")
    fail(file_, line(root), "compressor " + comp.substr(0, 40) + " not supported (zlib, vtkZLibDataCompressor, or none)");
  zlib_ = !comp.empty();
  const pugi::xml_node app = root.child("AppendedData");
  if (app) {
    const std::string enc = app.attribute("encoding").as_string("raw");
    if (enc != "raw" && enc != "base64") fail(file_, line(app), "AppendedData encoding '" + enc.substr(0, 40) + "'");
    appended_raw_ = enc == "raw";
  }
  const pugi::xml_node grid = root.child("UnstructuredGrid");
  if (!grid) fail(file_, line(root), "no UnstructuredGrid element");
  int pieces = 0;
  for (const pugi::xml_node& p : grid.children("Piece")) {
    if (pieces++ == 0) piece_ = p;
  }
  if (pieces != 1) fail(file_, line(grid), std::to_string(pieces) + " Piece elements (exactly one is read)");
}

std::vector<double> VtuReader::values(const pugi::xml_node& da, long long count, const std::string& what) {
  const std::optional<Scalar> s = scalar_of(da.attribute("type").value());
  if (!s) fail(file_, line(da), what + ": DataArray type '" + std::string(da.attribute("type").value()).substr(0, 40) + "' not supported");
  const std::string format = da.attribute("format").as_string("ascii");
  if (format == "ascii") return ascii(da, count, what);
  std::string bytes;
  const std::size_t need = static_cast<std::size_t>(count) * s->size;
  if (format == "binary") {
    DataBytes in(da.child_value(), true);
    bytes = binary(in, need, da, what);
  } else if (format == "appended") {
    const pugi::xml_attribute off = da.attribute("offset");
    if (!off) fail(file_, line(da), what + ": appended DataArray without offset");
    const long long o = detail::to_int(off.value(), file_, line(da), what + " offset", 0, kMaxCount);
    if (static_cast<std::size_t>(o) > appended_.size()) fail(file_, line(da), what + ": offset " + std::to_string(o) + " past the appended data");
    DataBytes in(appended_.substr(static_cast<std::size_t>(o)), !appended_raw_);
    bytes = binary(in, need, da, what);
  } else {
    fail(file_, line(da), what + ": format '" + format.substr(0, 40) + "' (ascii, binary or appended)");
  }
  std::vector<double> v(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = value_at(bytes.data() + i * s->size, *s, swap_);
  return v;
}

// The `bytes` bytes of one binary array: a header (the byte count, or for zlib the block
// table), then the data.
std::string VtuReader::binary(DataBytes& in, std::size_t bytes, const pugi::xml_node& da, const std::string& what) {
  auto truncated = [&]() {
    fail(file_, line(da), what + (in.bad() ? ": not base64 data" : ": data truncated"));
  };
  auto header_value = [&]() {
    std::string h;
    if (!in.take(header_bytes_, h)) truncated();
    return header_bytes_ == 8 ? detail::load_bytes<std::uint64_t>(h.data(), swap_)
                              : std::uint64_t{detail::load_bytes<std::uint32_t>(h.data(), swap_)};
  };
  std::string out;
  if (!zlib_) {
    const std::uint64_t n = header_value();
    if (n != bytes) fail(file_, line(da), what + ": " + std::to_string(n) + " bytes, expected " + std::to_string(bytes));
    if (bytes > in.bound() || !in.take(bytes, out)) truncated();
    return out;
  }
  const std::uint64_t blocks = header_value(), block = header_value(), last = header_value();
  if (blocks > in.bound() / header_bytes_) truncated();
  std::vector<std::uint64_t> sizes(blocks);
  for (auto& c : sizes) c = header_value();
  const std::uint64_t full = blocks == 0 ? 0 : (blocks - 1) * block + (last == 0 ? block : last);
  if (full != bytes || (blocks > 0 && block == 0) || last > block)
    fail(file_, line(da), what + ": compressed blocks of " + std::to_string(full) + " bytes, expected " + std::to_string(bytes));
  std::string packed;
  out.reserve(bytes);  // once: growing block by block would take up to twice the memory
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t want = b + 1 == blocks && last != 0 ? last : block;
    // zlib expands at most about 1032 to 1: a larger claim is a broken or hostile header
    if (sizes[b] > in.bound() || want > 1100 * sizes[b] + 64) truncated();
    packed.clear();
    if (!in.take(sizes[b], packed)) truncated();
    const std::size_t at = out.size();
    out.resize(at + want);
    uLongf got = static_cast<uLongf>(want);
    if (::uncompress(reinterpret_cast<Bytef*>(out.data() + at), &got, reinterpret_cast<const Bytef*>(packed.data()),
                     static_cast<uLong>(packed.size())) != Z_OK || got != want)
      fail(file_, line(da), what + ": zlib block " + std::to_string(b) + " does not decompress to " + std::to_string(want) + " bytes");
  }
  return out;
}

std::vector<double> VtuReader::ascii(const pugi::xml_node& da, long long count, const std::string& what) {
  const std::string_view text = da.child_value();
  if (static_cast<unsigned long long>(count) > text.size() / 2 + 1)
    fail(file_, line(da), what + ": " + std::to_string(count) + " values expected but the text is too short");
  std::vector<double> v;
  v.reserve(static_cast<std::size_t>(count));
  std::size_t i = 0;
  while (true) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i >= text.size()) break;
    std::size_t j = i;
    while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j]))) ++j;
    if (v.size() == static_cast<std::size_t>(count)) fail(file_, line(da), what + ": more than " + std::to_string(count) + " values");
    double x = 0;
    const auto [end, ec] = std::from_chars(text.data() + i, text.data() + j, x);
    if (ec != std::errc() || end != text.data() + j || !std::isfinite(x))  // named by to_double
      x = detail::to_double(text.substr(i, j - i), file_, line(da), what + " value " + std::to_string(v.size()));
    v.push_back(x);
    i = j;
  }
  if (v.size() != static_cast<std::size_t>(count))
    fail(file_, line(da), what + ": " + std::to_string(v.size()) + " values, expected " + std::to_string(count));
  return v;
}

}  // namespace

ControlMesh read_vtu_mesh(const path& file) { return parse_vtu_mesh(detail::slurp(file), file); }

namespace {
// `read` run, its std::bad_alloc (arrays within the inflation bound can still be larger than
// the memory this process may take) an error naming the file.
template <typename F>
auto naming_memory(const path& file, std::size_t bytes, F read) {
  try {
    return read();
  } catch (const std::bad_alloc&) {
    fail(file, 0, "not enough memory for its arrays (a file of " + std::to_string(bytes) + " bytes; zlib data may inflate 1100 times)");
  }
}
}  // namespace

ControlMesh parse_vtu_mesh(std::string_view data, const path& file) {
  return naming_memory(file, data.size(), [&] {
    VtuReader r(detail::skip_bom(data), file);
    const Eigen::MatrixXd P = r.points();
    return detail::vtk_control_mesh(P, r.cells(P.rows()), file);
  });
}

Eigen::MatrixXd read_vtu_points(const path& file) { return parse_vtu_points(detail::slurp(file), file); }

Eigen::MatrixXd parse_vtu_points(std::string_view data, const path& file) {
  return naming_memory(file, data.size(), [&] { return VtuReader(detail::skip_bom(data), file).points(); });
}

}  // namespace mbi::io

namespace mbi::io::detail {

PointData read_vtu_point_data(const path& file) {
  const std::string data = slurp(file);
  return naming_memory(file, data.size(), [&] {
    VtuReader r(skip_bom(data), file);
    PointData d;
    d.P = r.points();
    d.fields = r.fields(d.P.rows());
    return d;
  });
}

}  // namespace mbi::io::detail
