// numpy conversions and checks of the bindings (see arrays.hpp).
#include "arrays.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <type_traits>

namespace mbi::python {
namespace {

std::string shape_text(Shape s, const char* rows = "n", const char* cols = "d") {
  auto one = [](Eigen::Index v, const char* dflt) { return v >= 0 ? std::to_string(v) : std::string(dflt); };
  return "(" + one(s.rows, rows) + ", " + one(s.cols, cols) + ")";
}

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += (k ? ", " : "") + std::to_string(a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// "(rows, cols)", or "(frames, rows / frames, cols)" for frames > 0
std::string shape_text(Eigen::Index rows, Eigen::Index cols, Eigen::Index frames) {
  if (frames > 0) return "(" + std::to_string(frames) + ", " + std::to_string(rows / frames) + ", " + std::to_string(cols) + ")";
  return "(" + std::to_string(rows) + ", " + std::to_string(cols) + ")";
}

// out= must be (rows, cols), or (frames, rows / frames, cols) for frames > 0 (no strings built
// unless it is not: this runs every frame)
void check_output_shape(const py::array& a, const char* name, Eigen::Index rows, Eigen::Index cols,
                        Eigen::Index frames) {
  const bool ok = frames > 0 ? a.ndim() == 3 && a.shape(0) == frames && a.shape(1) == rows / frames && a.shape(2) == cols
                             : a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == cols;
  if (!ok) throw Error(std::string(name) + " must have shape " + shape_text(rows, cols, frames) + ", got " + shape_of(a));
}

std::string dtype_of(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

// obj as a numpy array (array-likes such as lists go through numpy.asarray).
py::array as_array(const py::handle& obj, const char* name) {
  if (obj.is_none()) throw Error(std::string(name) + " is missing (None)");
  if (py::isinstance<py::array>(obj)) return py::reinterpret_borrow<py::array>(obj);
  try {
    return py::module_::import("numpy").attr("asarray")(obj);
  } catch (py::error_already_set& e) {
    throw Error(std::string(name) + " is not an array: " + e.what());
  }
}

void check_shape(const py::array& a, const char* name, Shape want, py::ssize_t first_axis) {
  const Eigen::Index rows = a.shape(first_axis), cols = a.shape(first_axis + 1);
  if ((want.rows >= 0 && rows != want.rows) || (want.cols >= 0 && cols != want.cols))
    throw Error(std::string(name) + " must have shape " + (first_axis ? "(frames, " : "(") +
                shape_text(want).substr(1) + ", got " + shape_of(a));
}

// float64, native byte order, strides that are non-negative multiples of 8: readable in place
bool float64_in_place(const py::array& a) {
  if (!py::isinstance<py::array_t<double>>(a) || a.dtype().kind() != 'f') return false;
  for (py::ssize_t k = 0; k < a.ndim(); ++k)
    if (a.strides(k) < 0 || a.strides(k) % static_cast<py::ssize_t>(sizeof(double)) != 0) return false;
  return true;
}

void check_float_dtype(const py::array& a, const char* name) {
  if (a.dtype().kind() != 'f')
    throw Error(std::string(name) + " must be a float array (float64), got dtype " + dtype_of(a));
}

void check_finite(const ConstMap& A, const char* name) {
  for (Eigen::Index c = 0; c < A.cols(); ++c)
    for (Eigen::Index i = 0; i < A.rows(); ++i)
      if (!std::isfinite(A(i, c)))
        throw Error(std::string(name) + "[" + std::to_string(i) + ", " + std::to_string(c) + "] is not finite (" +
                    std::to_string(A(i, c)) + ")");
}

Eigen::Index stride_of(const py::array& a, py::ssize_t axis) { return a.strides(axis) / static_cast<py::ssize_t>(sizeof(double)); }

}  // namespace

Input float_matrix(const py::handle& obj, const char* name, Shape shape, bool finite) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 2)
    throw Error(std::string(name) + " must be a 2D array " + shape_text(shape) + ", got shape " + shape_of(a));
  check_shape(a, name, shape, 0);
  check_float_dtype(a, name);
  if (!float64_in_place(a)) a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  Input in{a, ConstMap(static_cast<const double*>(a.data()), a.shape(0), a.shape(1),
                       Stride(stride_of(a, 1), stride_of(a, 0)))};
  if (finite) check_finite(in.map, name);
  return in;
}

Input float_batch(const py::handle& obj, const char* name, Shape shape, Eigen::Index& frames, bool finite) {
  py::array a = as_array(obj, name);
  if (a.ndim() == 2) {
    frames = 0;
    return float_matrix(a, name, shape, finite);
  }
  if (a.ndim() != 3)
    throw Error(std::string(name) + " must be " + shape_text(shape) + " or a batch (frames, " +
                shape_text(shape).substr(1) + ", got shape " + shape_of(a));
  check_shape(a, name, shape, 1);
  check_float_dtype(a, name);
  frames = a.shape(0);
  // frames stacked as (frames n) x d rows: frame k + 1 must start where frame k's rows would go on
  const bool stacked = frames <= 1 || a.strides(0) == a.shape(1) * a.strides(1);
  if (!float64_in_place(a) || !stacked) a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  Input in{a, ConstMap(static_cast<const double*>(a.data()), a.shape(0) * a.shape(1), a.shape(2),
                       Stride(stride_of(a, 2), stride_of(a, 1)))};
  if (finite) check_finite(in.map, name);
  return in;
}

Eigen::VectorXd float_vector(const py::handle& obj, const char* name, Eigen::Index size) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 1 || a.shape(0) != size)
    throw Error(std::string(name) + " must have shape (" + std::to_string(size) + ",), got " + shape_of(a));
  // (0, -9.81, 0) and (1, 0, 0) alike: integers are exact as float64 here
  if (a.dtype().kind() == 'i' || a.dtype().kind() == 'u') a = a.attr("astype")("float64");
  const Input in = float_matrix(a.attr("reshape")(size, 1), name, {size, 1});
  return in.map.col(0);
}

std::vector<int> index_list(const py::handle& obj, const char* name) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 1) throw Error(std::string(name) + " must be a 1D list of indices, got shape " + shape_of(a));
  if (a.shape(0) == 0) return {};  // [] is float64 to numpy
  const Eigen::MatrixXi m = index_matrix(a.attr("reshape")(a.shape(0), 1), name, {a.shape(0), 1});
  return {m.data(), m.data() + m.size()};
}

Eigen::MatrixXi index_matrix(const py::handle& obj, const char* name, Shape shape) {
  py::array a = as_array(obj, name);
  if (a.ndim() != 2)
    throw Error(std::string(name) + " must be a 2D integer array " + shape_text(shape, "m", "d+1") +
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
  if (kind == 'u') put(py::array_t<std::uint64_t, py::array::forcecast>::ensure(a));
  else put(py::array_t<std::int64_t, py::array::forcecast>::ensure(a));
  return out;
}

Mesh control_mesh(const py::handle& U, const py::handle& T) {
  Input u = float_matrix(U, "U");
  return {u, index_matrix(T, "T", {-1, u.map.cols() + 1})};
}

Output float_output(const py::handle& out, const char* name, Eigen::Index rows, Eigen::Index cols, Eigen::Index frames) {
  const Eigen::Index per = frames > 0 ? rows / frames : rows;
  if (out.is_none()) {
    py::array_t<double> a = frames > 0 ? py::array_t<double>({frames, per, cols}) : py::array_t<double>({rows, cols});
    return {a, Map(a.mutable_data(), rows, cols, Stride(1, cols))};
  }
  if (!py::isinstance<py::array>(out)) throw Error(std::string(name) + " must be a numpy array");
  py::array a = py::reinterpret_borrow<py::array>(out);
  check_output_shape(a, name, rows, cols, frames);
  if (!float64_in_place(a))
    throw Error(std::string(name) + " must be a float64 array with positive strides, got dtype " + dtype_of(a));
  if (!a.writeable()) throw Error(std::string(name) + " is read-only");
  const py::ssize_t ax = frames > 0 ? 1 : 0;
  if (frames > 1 && a.strides(0) != a.shape(1) * a.strides(1))
    throw Error(std::string(name) + ": its frames must follow one another (a C-order array, or a slice of frames)");
  return {a, Map(static_cast<double*>(a.mutable_data()), rows, cols, Stride(stride_of(a, ax + 1), stride_of(a, ax)))};
}

std::pair<py::array, FloatMap> float32_output(const py::handle& out, const char* name, Eigen::Index rows,
                                              Eigen::Index cols, Eigen::Index frames) {
  const Eigen::Index per = frames > 0 ? rows / frames : rows;
  if (out.is_none()) {
    py::array_t<float> a = frames > 0 ? py::array_t<float>({frames, per, cols}) : py::array_t<float>({rows, cols});
    return {a, FloatMap(a.mutable_data(), rows, cols)};
  }
  if (!py::isinstance<py::array>(out)) throw Error(std::string(name) + " must be a numpy array");
  py::array a = py::reinterpret_borrow<py::array>(out);
  check_output_shape(a, name, rows, cols, frames);
  if (!py::isinstance<py::array_t<float>>(a) || a.dtype().kind() != 'f')
    throw Error(std::string(name) + " must be a float32 array, got dtype " + dtype_of(a));
  if (!(a.flags() & py::array::c_style)) throw Error(std::string(name) + " must be C-contiguous");
  if (!a.writeable()) throw Error(std::string(name) + " is read-only");
  return {a, FloatMap(static_cast<float*>(a.mutable_data()), rows, cols)};
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

void check_no_overlap(const py::array& out, const py::array& in, const char* out_name, const char* in_name) {
  auto extent = [](const py::array& a) {
    auto lo = reinterpret_cast<std::uintptr_t>(a.data()), hi = lo;
    for (py::ssize_t k = 0; k < a.ndim(); ++k) {
      if (a.shape(k) == 0) return std::pair<std::uintptr_t, std::uintptr_t>{0, 0};
      const py::ssize_t span = (a.shape(k) - 1) * a.strides(k);
      (span < 0 ? lo : hi) += span;
    }
    return std::pair<std::uintptr_t, std::uintptr_t>{lo, hi + static_cast<std::uintptr_t>(a.itemsize())};
  };
  const auto [a0, a1] = extent(out);
  const auto [b0, b1] = extent(in);
  if (a0 < b1 && b0 < a1) throw Error(std::string(out_name) + " shares memory with " + in_name);
}

}  // namespace mbi::python
