// numpy conversions and checks of the bindings (see arrays.hpp).
#include "arrays.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <type_traits>
#include <vector>

namespace mbi::python {
namespace {

// The letter docs/python.md gives the rows of an argument whose row count is not fixed: n
// control vertices, p dense points, m elements, t triangles.
const char* row_letter(const char* name) {
  const std::string n = name;
  if (n == "P" || n == "G" || n == "rest_normals" || n == "normals") return "p";
  if (n == "T") return "m";
  if (n == "F") return "t";
  return "n";
}

std::string shape_text(Shape s, const char* rows = "n", const char* cols = "d") {
  auto one = [](Eigen::Index v, const char* dflt) { return v >= 0 ? std::to_string(v) : std::string(dflt); };
  return "(" + one(s.rows, rows) + ", " + one(s.cols, cols) + ")";
}

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += (k ? ", " : "") + std::to_string(a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string shape_text(const std::vector<py::ssize_t>& shape) {
  std::string s = "(";
  for (size_t k = 0; k < shape.size(); ++k) s += (k ? ", " : "") + std::to_string(shape[k]);
  return s + ")";
}

// The shape of an output: (rows, cols), or (frames, rows, cols) for a batch.
std::vector<py::ssize_t> output_shape(Eigen::Index rows, Eigen::Index cols, Frames frames) {
  if (frames.batch) return {frames.count, rows, cols};
  return {rows, cols};
}

std::string dtype_of(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

// obj as a numpy array (array-likes such as lists go through numpy.asarray).
py::array as_array(const py::handle& obj, const char* name) {
  if (obj.is_none()) throw Error(std::string(name) + " is missing (None)");
  if (py::isinstance<py::array>(obj)) return py::reinterpret_borrow<py::array>(obj);
  if (py::hasattr(obj, "requires_grad") && py::bool_(obj.attr("requires_grad")))
    throw Error(std::string(name) + " is a tensor that requires grad: numpy cannot read it; use mbi.torch " +
                "(mbi.torch.deform(deformer, X)) for gradients, or pass " + name + ".detach()");
  try {
    return py::module_::import("numpy").attr("asarray")(obj);
  } catch (py::error_already_set& e) {  // the exception's message alone, without its traceback
    throw Error(std::string(name) + " is not an array: " + py::str(e.value()).cast<std::string>());
  }
}

void check_shape(const py::array& a, const char* name, Shape want, py::ssize_t first_axis) {
  const Eigen::Index rows = a.shape(first_axis), cols = a.shape(first_axis + 1);
  if ((want.rows >= 0 && rows != want.rows) || (want.cols >= 0 && cols != want.cols))
    throw Error(std::string(name) + " must have shape " + (first_axis ? "(frames, " : "(") +
                shape_text(want, row_letter(name)).substr(1) + ", got " + shape_of(a));
}

// Floats, or integers (exact in float64 up to 2^53: positions on a grid, lists of ints).
void check_float_dtype(const py::array& a, const char* name) {
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw Error(std::string(name) + " must be a float array (float64; integers are taken too), got dtype " +
                dtype_of(a));
}

// True when no value of the span is an infinity or a NaN, the only doubles whose 11 exponent bits
// are all ones: adding one to the exponent field then carries into bit 31 of the high word. Integer
// arithmetic the compiler vectorises (3 to 4x faster than a std::isfinite branch a value).
bool all_finite(const double* v, Eigen::Index count) {
  std::uint32_t carry = 0;
  for (Eigen::Index i = 0; i < count; ++i) {
    std::uint64_t bits;
    std::memcpy(&bits, v + i, sizeof bits);
    carry |= (static_cast<std::uint32_t>(bits >> 32) & 0x7ff00000U) + 0x00100000U;
  }
  return (carry & 0x80000000U) == 0;
}

void check_finite(const ConstMap& A, const char* name) {
  const bool packed = (A.innerStride() == 1 && A.outerStride() == A.rows()) ||
                      (A.outerStride() == 1 && A.innerStride() == A.cols());  // Fortran or C order
  if (packed && all_finite(A.data(), A.size())) return;
  for (Eigen::Index c = 0; c < A.cols(); ++c)
    for (Eigen::Index i = 0; i < A.rows(); ++i)
      if (!std::isfinite(A(i, c)))
        throw Error(std::string(name) + "[" + std::to_string(i) + ", " + std::to_string(c) + "] is not finite (" +
                    std::to_string(A(i, c)) + ")");
}

// A new array's pages are mapped on their first write. The evaluation's threads writing into a
// fresh array fault its (huge) pages in at the same time and wait on each other: a first 600 MB
// batch ran 3.6x slower a frame than into memory written before. Zeros written first, one part
// a core, each part on its own 2 MB-aligned range (no huge page shared), map them for arrays of
// at least kPrefaultBytes.
constexpr size_t kPrefaultBytes = size_t(4) << 20;
constexpr size_t kHugePage = size_t(2) << 20;

void prefault(char* data, size_t bytes) {
  const size_t cores = std::max(1u, std::thread::hardware_concurrency());
  const size_t parts = std::min<size_t>(cores, bytes / kHugePage);
  auto part = [&](size_t k) {  // [begin, end) of part k, cut at 2 MB-aligned addresses
    auto cut = [&](size_t j) {
      if (j == 0) return data;
      if (j == parts) return data + bytes;
      const auto at = reinterpret_cast<std::uintptr_t>(data) + bytes / parts * j;
      return data + ((at / kHugePage) * kHugePage - reinterpret_cast<std::uintptr_t>(data));
    };
    std::memset(cut(k), 0, static_cast<size_t>(cut(k + 1) - cut(k)));
  };
  std::vector<std::thread> helpers;
  for (size_t k = 1; k < parts; ++k) helpers.emplace_back(part, k);
  part(0);
  for (std::thread& t : helpers) t.join();
}

template <class T>
T* prefaulted(py::array_t<T>& a) {
  T* data = a.mutable_data();
  const size_t bytes = static_cast<size_t>(a.nbytes());
  if (bytes >= kPrefaultBytes) {
    py::gil_scoped_release release;
    prefault(reinterpret_cast<char*>(data), bytes);
  }
  return data;
}

bool aligned(const py::array& a) {
  return (py::detail::array_proxy(a.ptr())->flags & py::detail::npy_api::NPY_ARRAY_ALIGNED_) != 0;
}

// A 2D array, or a 3D batch seen as (frames rows) x cols, as rows, cols and byte strides;
// merged is false when a batch's frames are not one row stride apart. The stride of an axis of
// one element or none is never used.
struct Layout {
  Eigen::Index rows, cols;
  py::ssize_t row_stride, col_stride;
  bool merged = true;
};

Layout layout_of(const py::array& a) {
  const py::ssize_t ax = a.ndim() - 2;
  Layout l{a.shape(ax) * (ax ? a.shape(0) : 1), a.shape(ax + 1), a.strides(ax), a.strides(ax + 1)};
  if (ax && a.shape(0) > 1) {
    if (a.shape(1) <= 1) l.row_stride = a.strides(0);
    else l.merged = a.strides(0) == a.shape(1) * a.strides(1);
  }
  return l;
}

// Whether Eigen can view the layout: every stride that is used a positive multiple of the item
// (Eigen::Ref reads a zero stride as "contiguous"; negative ones are left to numpy).
bool mappable(const Layout& l, py::ssize_t item) {
  auto ok = [item](Eigen::Index extent, py::ssize_t stride) { return extent <= 1 || (stride > 0 && stride % item == 0); };
  return l.merged && ok(l.rows, l.row_stride) && ok(l.cols, l.col_stride);
}

// Eigen's (outer, inner) strides in items of a mappable layout (1 where unused).
Stride eigen_stride(const Layout& l, py::ssize_t item) {
  return Stride(l.cols > 1 ? l.col_stride / item : 1, l.rows > 1 ? l.row_stride / item : 1);
}

// a as a float64 map: in place when native float64, aligned and mappable, else a C-order copy
// (zero or negative strides, frames apart, other float types and byte orders).
Input read_floats(const py::array& a, const char* name, bool finite) {
  py::array data = a;
  if (!py::isinstance<py::array_t<double>>(a) || !aligned(a) || !mappable(layout_of(a), sizeof(double)))
    data = a.attr("astype")("float64", py::arg("order") = "C");
  const Layout l = layout_of(data);
  Input in{name, a, data, ConstMap(static_cast<const double*>(data.data()), l.rows, l.cols, eigen_stride(l, sizeof(double)))};
  if (finite) check_finite(in.map, name);
  return in;
}

// Whether two elements of a share memory: sorted by stride, each axis must step past all the
// elements of the axes below it (a sufficient test; a zero stride fails it).
bool overlaps_itself(const py::array& a) {
  std::vector<std::pair<py::ssize_t, py::ssize_t>> axes;  // |stride|, extent
  for (py::ssize_t k = 0; k < a.ndim(); ++k) {
    if (a.shape(k) == 0) return false;
    if (a.shape(k) > 1) axes.emplace_back(std::abs(a.strides(k)), a.shape(k));
  }
  std::sort(axes.begin(), axes.end());
  py::ssize_t span = a.itemsize();
  for (const auto& [stride, extent] : axes) {
    if (stride < span) return true;
    span += stride * (extent - 1);
  }
  return false;
}

// out= of `shape` and float dtype of `itemsize` bytes, writable, not overlapping itself.
py::array checked_out(const py::handle& out, const char* name, const std::vector<py::ssize_t>& shape,
                      py::ssize_t itemsize) {
  if (!py::isinstance<py::array>(out)) throw Error(std::string(name) + " must be a numpy array");
  py::array a = py::reinterpret_borrow<py::array>(out);
  bool same = a.ndim() == static_cast<py::ssize_t>(shape.size());
  for (py::ssize_t k = 0; same && k < a.ndim(); ++k) same = a.shape(k) == shape[static_cast<size_t>(k)];
  if (!same) throw Error(std::string(name) + " must have shape " + shape_text(shape) + ", got " + shape_of(a));
  if (a.dtype().kind() != 'f' || a.itemsize() != itemsize)
    throw Error(std::string(name) + " must be a " + (itemsize == 4 ? "float32" : "float64") + " array, got dtype " +
                dtype_of(a));
  if (!a.writeable()) throw Error(std::string(name) + " is read-only");
  if (overlaps_itself(a))
    throw Error(std::string(name) + " overlaps itself (a zero stride, or rows that share memory): it cannot be written");
  return a;
}

// [lo, hi) of the bytes a spans; empty for an empty array
std::pair<std::uintptr_t, std::uintptr_t> extent(const py::array& a) {
  auto lo = reinterpret_cast<std::uintptr_t>(a.data()), hi = lo;
  for (py::ssize_t k = 0; k < a.ndim(); ++k) {
    if (a.shape(k) == 0) return {0, 0};
    const py::ssize_t span = (a.shape(k) - 1) * a.strides(k);
    (span < 0 ? lo : hi) += static_cast<std::uintptr_t>(span);  // modular: adds a negative span
  }
  return {lo, hi + static_cast<std::uintptr_t>(a.itemsize())};
}

}  // namespace

Input float_matrix(const py::handle& obj, const char* name, Shape shape, bool finite) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 2)
    throw Error(std::string(name) + " must be a 2D array " + shape_text(shape, row_letter(name)) + ", got shape " +
                shape_of(a));
  check_shape(a, name, shape, 0);
  check_float_dtype(a, name);
  return read_floats(a, name, finite);
}

Input float_batch(const py::handle& obj, const char* name, Shape shape, Frames& frames, bool finite) {
  py::array a = as_array(obj, name);
  if (a.ndim() == 2) {
    frames = {};
    return float_matrix(a, name, shape, finite);
  }
  if (a.ndim() != 3)
    throw Error(std::string(name) + " must be " + shape_text(shape, row_letter(name)) + " or a batch (frames, " +
                shape_text(shape, row_letter(name)).substr(1) + ", got shape " + shape_of(a));
  check_shape(a, name, shape, 1);
  check_float_dtype(a, name);
  frames = {a.shape(0), true};
  return read_floats(a, name, finite);
}

Eigen::VectorXd float_vector(const py::handle& obj, const char* name, Eigen::Index size) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 1 || a.shape(0) != size)
    throw Error(std::string(name) + " must have shape (" + std::to_string(size) + ",), got " + shape_of(a));
  const Input in = float_matrix(a.attr("reshape")(size, 1), name, {size, 1});
  return in.map.col(0);
}

std::vector<int> index_list(const py::handle& obj, const char* name, Eigen::Index size) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 1)
    throw Error(std::string(name) + " must be a 1D list of indices or a boolean mask, got shape " + shape_of(a));
  if (a.dtype().kind() == 'b') {  // a mask: one entry a node, True where taken
    if (size >= 0 && a.shape(0) != size)
      throw Error(std::string(name) + " is a boolean mask of " + std::to_string(a.shape(0)) + " entries; it needs " +
                  std::to_string(size) + ", one a node");
    a = py::module_::import("numpy").attr("flatnonzero")(a);
  }
  if (a.shape(0) == 0) return {};  // [] is float64 to numpy
  const Eigen::MatrixXi m = index_matrix(a.attr("reshape")(a.shape(0), 1), name, {a.shape(0), 1});
  return {m.data(), m.data() + m.size()};
}

Eigen::MatrixXi index_matrix(const py::handle& obj, const char* name, Shape shape) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 2)
    throw Error(std::string(name) + " must be a 2D integer array " + shape_text(shape, row_letter(name), "d+1") +
                ", got shape " + shape_of(a));
  check_shape(a, name, shape, 0);
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw Error(std::string(name) + " must be an integer array, got dtype " + dtype_of(a));
  Eigen::MatrixXi out(a.shape(0), a.shape(1));
  auto put = [&](auto values) {
    auto v = values.template unchecked<2>();
    for (py::ssize_t i = 0; i < v.shape(0); ++i)
      for (py::ssize_t j = 0; j < v.shape(1); ++j) {
        const auto x = v(i, j);
        bool fits;
        if constexpr (std::is_unsigned_v<decltype(x)>) fits = x <= static_cast<std::uint64_t>(INT_MAX);
        else fits = x >= INT_MIN && x <= INT_MAX;
        if (!fits)
          throw Error(std::string(name) + "[" + std::to_string(i) + ", " + std::to_string(j) + "] = " +
                      std::to_string(x) + " is out of range (indices fit in 32 bits)");
        out(i, j) = static_cast<int>(x);
      }
  };
  if (!aligned(a)) a = a.attr("copy")();  // ensure() would keep an unaligned array of the right type
  if (kind == 'u') put(py::array_t<std::uint64_t, py::array::forcecast>::ensure(a));
  else put(py::array_t<std::int64_t, py::array::forcecast>::ensure(a));
  return out;
}

Mesh control_mesh(const py::handle& U, const py::handle& T) {
  Input u = float_matrix(U, "U");
  return {u, index_matrix(T, "T", {-1, u.map.cols() + 1})};
}

template <class MapType>
py::array OutputOf<MapType>::finish() const {
  if (scratch) py::module_::import("numpy").attr("copyto")(array, scratch);
  return array;
}
template struct OutputOf<Map>;
template struct OutputOf<FloatMap>;

Output float_output(const py::handle& out, const char* name, Eigen::Index rows, Eigen::Index cols, Frames frames) {
  const std::vector<py::ssize_t> shape = output_shape(rows, cols, frames);
  const Eigen::Index total = frames.count * rows;
  const Stride c_order(1, std::max<Eigen::Index>(cols, 1));
  if (out.is_none()) {
    py::array_t<double> a(shape);
    return {name, a, py::object(), Map(prefaulted(a), total, cols, c_order)};
  }
  py::array a = checked_out(out, name, shape, sizeof(double));
  const Layout l = layout_of(a);
  if (py::isinstance<py::array_t<double>>(a) && aligned(a) && mappable(l, sizeof(double)))
    return {name, a, py::object(), Map(static_cast<double*>(a.mutable_data()), total, cols, eigen_stride(l, sizeof(double)))};
  py::array_t<double> scratch(shape);
  return {name, a, scratch, Map(prefaulted(scratch), total, cols, c_order)};
}

Output32 float32_output(const py::handle& out, const char* name, Eigen::Index rows, Eigen::Index cols, Frames frames) {
  const std::vector<py::ssize_t> shape = output_shape(rows, cols, frames);
  const Eigen::Index total = frames.count * rows;
  if (out.is_none()) {
    py::array_t<float> a(shape);
    return {name, a, py::object(), FloatMap(prefaulted(a), total, cols)};
  }
  py::array a = checked_out(out, name, shape, sizeof(float));
  if (py::isinstance<py::array_t<float>>(a) && aligned(a) && (a.flags() & py::array::c_style))
    return {name, a, py::object(), FloatMap(static_cast<float*>(a.mutable_data()), total, cols)};
  py::array_t<float> scratch(shape);
  return {name, a, scratch, FloatMap(prefaulted(scratch), total, cols)};
}

py::array readonly_view(const py::dtype& dtype, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides,
                        const void* data, const py::handle& owner) {
  py::array a(dtype, std::move(shape), std::move(strides), data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

Eigen::Ref<const Eigen::MatrixXd> columns(const ConstMap& A, Eigen::MatrixXd& scratch) {
  if (A.innerStride() == 1)
    return Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>(A.data(), A.rows(), A.cols(),
                                                                      Eigen::OuterStride<>(A.outerStride()));
  scratch = A;
  return scratch;
}

py::array to_numpy(Eigen::MatrixXd&& A) {
  auto* owned = new Eigen::MatrixXd(std::move(A));
  py::capsule owner(owned, [](void* p) { delete static_cast<Eigen::MatrixXd*>(p); });
  const py::ssize_t s = sizeof(double);
  return py::array_t<double>({owned->rows(), owned->cols()}, {s, s * owned->rows()}, owned->data(), owner);
}

py::array to_numpy(const Eigen::Ref<const Eigen::MatrixXd>& A) {
  py::array_t<double> a({A.rows(), A.cols()});
  Map(a.mutable_data(), A.rows(), A.cols(), Stride(1, A.cols())) = A;
  return a;
}

py::array to_numpy(const Eigen::MatrixXi& A) {
  py::array_t<int> a({A.rows(), A.cols()});
  Eigen::Map<Eigen::MatrixXi, 0, Stride>(a.mutable_data(), A.rows(), A.cols(), Stride(1, A.cols())) = A;
  return a;
}

py::array to_numpy_vector(const Eigen::Ref<const Eigen::VectorXd>& v) {
  py::array_t<double> a(v.size());
  Eigen::Map<Eigen::VectorXd>(a.mutable_data(), v.size()) = v;
  return a;
}

void check_disjoint(const py::array& out, const char* out_name, const py::array& other, const char* other_name) {
  const auto [a0, a1] = extent(out);
  const auto [b0, b1] = extent(other);
  if (!(a0 < b1 && b0 < a1)) return;
  // their spans meet: numpy decides whether an element is shared (interleaved rows are not)
  bool shared = true;
  try {
    shared = py::module_::import("numpy").attr("shares_memory")(out, other, py::arg("max_work") = 1 << 20).cast<bool>();
  } catch (py::error_already_set&) {  // numpy.TooHardError: taken as shared
  }
  if (shared) throw Error(std::string(out_name) + " shares memory with " + other_name);
}

}  // namespace mbi::python
