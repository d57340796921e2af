#pragma once
// numpy arrays in and out of the C++ libraries: every check of a shape, dtype, layout and value
// that the bindings make, with messages that name the argument. Inputs are read where they are
// (float64 with positive strides) or copied once (any other layout: zero and negative strides,
// other float types, integer indices); outputs are written where the caller wants them (out=,
// through a scratch copy when its layout cannot be mapped) or into a new C-order array. Every
// failure throws mbi::Error, which Python sees as mbi.Error (a ValueError). Eigen must never see
// a zero stride: Eigen::Ref reads a stride of 0 as "contiguous".
#include <mbi/error.hpp>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace mbi::python {

namespace py = pybind11;

using Stride = Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>;
using ConstMap = Eigen::Map<const Eigen::MatrixXd, 0, Stride>;
using Map = Eigen::Map<Eigen::MatrixXd, 0, Stride>;
using FloatMap = Eigen::Map<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

/// A float64 matrix read in place: `array` keeps the memory alive (the caller's array, or the
/// converted copy), `map` views it (rows x cols, strides > 0). `source` is the caller's array
/// as given (what an output must not overlap), `name` the argument's name.
struct Input {
  const char* name = "";
  py::array source, array;
  ConstMap map{nullptr, 0, 0, Stride(1, 1)};
};

/// Frames of a batch: a (count, rows, cols) array seen as (count rows) x cols, or (batch false)
/// one (rows, cols) array, count 1.
struct Frames {
  Eigen::Index count = 1;
  bool batch = false;
};

/// Shape wanted for an argument: -1 = any.
struct Shape {
  Eigen::Index rows = -1, cols = -1;
};

/// A 2D float array (float64 read in place when its strides are positive and it is aligned;
/// any other layout, float16/32, long double and other byte orders converted into a C-order
/// copy), of `shape`, finite unless finite = false. name: the argument's name in messages.
Input float_matrix(const py::handle& obj, const char* name, Shape shape = {}, bool finite = true);

/// A 2D float array (n x d) or a batch of them (frames x n x d, frames >= 0), as (frames n) x d
/// rows, read as float_matrix reads; frames receives the batch's layout.
Input float_batch(const py::handle& obj, const char* name, Shape shape, Frames& frames, bool finite = true);

/// A 2D integer array of `shape` (any signed or unsigned integer type, checked to fit in int32).
Eigen::MatrixXi index_matrix(const py::handle& obj, const char* name, Shape shape = {});

/// A vector of `size` floats (a list, a tuple or a 1D array), finite: a point, a direction, a
/// force.
Eigen::VectorXd float_vector(const py::handle& obj, const char* name, Eigen::Index size);
inline Eigen::Vector3d vector3(const py::handle& obj, const char* name) { return float_vector(obj, name, 3); }

/// A 1D list of indices (any integer type, checked to fit in int32), or a boolean mask of `size`
/// entries (-1: any) giving the indices where it is True: node sets.
std::vector<int> index_list(const py::handle& obj, const char* name, Eigen::Index size = -1);

/// A control mesh: U (n, d) rest vertices read in place, T (m, d+1) elements.
struct Mesh {
  Input U;
  Eigen::MatrixXi T;
};
Mesh control_mesh(const py::handle& U, const py::handle& T);

/// An output to write: `array` is what the call returns (the caller's out= or a new C-order
/// array); `map` views it, or, when out= is a layout that cannot be mapped (negative strides,
/// frames apart, unaligned, another byte order, for float32 anything but C order), a C-order
/// `scratch` array that finish() copies into out=.
template <class MapType>
struct OutputOf {
  const char* name;
  py::array array;
  py::object scratch;  // null when map views array
  MapType map;
  /// The array to return, holding what was written into map.
  py::array finish() const;
};
using Output = OutputOf<Map>;
using Output32 = OutputOf<FloatMap>;

/// A float64 output of rows x cols per frame (frames as the batch read: (count, rows, cols)
/// when frames.batch): `out` or, when out is None, a new C-order array. Refused with
/// mbi.Error, before anything is written: out= not a numpy array, of another shape or dtype,
/// read-only, or overlapping itself (a zero stride, rows that share memory).
Output float_output(const py::handle& out, const char* name, Eigen::Index rows, Eigen::Index cols,
                    Frames frames = {});

/// The same in float32, mapped as C-order rows (the fast kernel's interleaved layout).
Output32 float32_output(const py::handle& out, const char* name, Eigen::Index rows, Eigen::Index cols,
                        Frames frames = {});

/// Throws unless `out` shares no memory with `other` (numpy.shares_memory; an output written
/// while its input is read, or two outputs of one call).
void check_disjoint(const py::array& out, const char* out_name, const py::array& other, const char* other_name);
template <class MapType>
void check_disjoint(const OutputOf<MapType>& out, std::initializer_list<const Input*> inputs) {
  for (const Input* in : inputs) check_disjoint(out.array, out.name, in->source, in->name);
}
template <class A, class B>
void check_disjoint(const OutputOf<A>& a, const OutputOf<B>& b) {
  check_disjoint(a.array, a.name, b.array, b.name);
}

/// A numpy view of memory owned by `owner` (read-only: changing it would change the owner).
py::array readonly_view(const py::dtype& dtype, std::vector<py::ssize_t> shape,
                        std::vector<py::ssize_t> strides, const void* data, const py::handle& owner);

/// A's columns as Eigen::Ref<const MatrixXd> takes them: in place when each column is
/// contiguous (a Fortran-order array, such as the Bezier points this module returns), else
/// copied into `scratch`.
Eigen::Ref<const Eigen::MatrixXd> columns(const ConstMap& A, Eigen::MatrixXd& scratch);

/// A numpy array that takes A over (no copy; Fortran order).
py::array to_numpy(Eigen::MatrixXd&& A);
/// A new numpy array holding a copy of A (C-order).
py::array to_numpy(const Eigen::Ref<const Eigen::MatrixXd>& A);
py::array to_numpy(const Eigen::MatrixXi& A);
/// A C-order copy of an (n, d) result shaped like positions (dL/dX: the layout of X and of
/// Deformer.vjp's result).
inline py::array c_order(const Eigen::MatrixXd& A) { return to_numpy(Eigen::Ref<const Eigen::MatrixXd>(A)); }
py::array to_numpy_vector(const Eigen::Ref<const Eigen::VectorXd>& v);

}  // namespace mbi::python
