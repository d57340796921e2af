#pragma once
// numpy arrays in and out of the C++ libraries: every check of a shape, dtype, layout and value
// that the bindings make, with messages that name the argument. Inputs are read where they are
// (float64, any strides) or converted once (other float types, integer indices); outputs are
// written where the caller wants them (out=) or into a new C-order array. Every failure throws
// mbi::Error, which Python sees as mbi.Error (a ValueError).
#include <mbi/error.hpp>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

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
/// converted copy), `map` views it (rows x cols, any strides).
struct Input {
  py::array array;
  ConstMap map{nullptr, 0, 0, Stride(0, 0)};
};

/// A float64 matrix to write: the caller's out= array or a new C-order one.
struct Output {
  py::array array;
  Map map{nullptr, 0, 0, Stride(0, 0)};
};

/// Shape wanted for an argument: -1 = any.
struct Shape {
  Eigen::Index rows = -1, cols = -1;
};

/// A 2D float array (float64 read in place; float16/32 and long double converted), of `shape`,
/// finite unless finite = false. name: the argument's name in messages.
Input float_matrix(const py::handle& obj, const char* name, Shape shape = {}, bool finite = true);

/// A 2D float array (n x d) or a batch of them (frames x n x d), as (frames n) x d rows. frames
/// receives the number of frames, or 0 when obj is 2D.
Input float_batch(const py::handle& obj, const char* name, Shape shape, Eigen::Index& frames, bool finite = true);

/// A 2D integer array of `shape` (any signed or unsigned integer type, checked to fit in int32).
Eigen::MatrixXi index_matrix(const py::handle& obj, const char* name, Shape shape = {});

/// A vector of `size` floats (a list, a tuple or a 1D array), finite: a point, a direction, a
/// force.
Eigen::VectorXd float_vector(const py::handle& obj, const char* name, Eigen::Index size);
inline Eigen::Vector3d vector3(const py::handle& obj, const char* name) { return float_vector(obj, name, 3); }

/// A 1D list of indices (any integer type, checked to fit in int32): node lists.
std::vector<int> index_list(const py::handle& obj, const char* name);

/// A control mesh: U (n, d) rest vertices read in place, T (m, d+1) elements.
struct Mesh {
  Input U;
  Eigen::MatrixXi T;
};
Mesh control_mesh(const py::handle& U, const py::handle& T);

/// An output of rows x cols float64: `out` (a writable float64 numpy array of that shape, any
/// strides) or, when out is None, a new C-order array. frames > 0: a (frames, rows/frames, cols)
/// array seen as rows x cols.
Output float_output(const py::handle& out, const char* name, Eigen::Index rows, Eigen::Index cols,
                    Eigen::Index frames = 0);

/// An output of rows x cols float32, C-contiguous (the fast kernel's interleaved layout); frames
/// as in float_output.
std::pair<py::array, FloatMap> float32_output(const py::handle& out, const char* name, Eigen::Index rows,
                                              Eigen::Index cols, Eigen::Index frames = 0);

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
py::array to_numpy_vector(const Eigen::Ref<const Eigen::VectorXd>& v);

/// Throws unless `out` and `in` share no memory (an output written while its input is read).
void check_no_overlap(const py::array& out, const py::array& in, const char* out_name, const char* in_name);

}  // namespace mbi::python
