// The Python array intake (python/src/arrays.hpp) in an embedded interpreter, so that the
// sanitizer build checks it without building the module: arrays in every layout of
// python/tests/layouts.py are read through Eigen::Ref (as the libraries take them) and outputs
// written through their maps; ASan and UBSan see any access outside the arrays.
#include "arrays.hpp"

#include <catch2/catch.hpp>
#include <pybind11/embed.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace mbi::python;

namespace {

// numpy, in the interpreter started once for all cases and never finalized (numpy cannot be
// imported again after Py_Finalize).
py::object numpy() {
  static const bool started = [] {
    py::initialize_interpreter();
    py::module_::import("sys").attr("path").attr("insert")(0, MBI_PYTHON_TESTS_DIR);
    return true;
  }();
  (void)started;
  return py::module_::import("numpy");
}

// python/tests/layouts.py, from the source tree.
py::module_ layouts() {
  numpy();
  return py::module_::import("layouts");
}

// values of `shape` (2D or a 3D batch): entry k is k / 8 - 3 (exact in float16)
py::array values(const std::vector<py::ssize_t>& shape) {
  py::ssize_t size = 1;
  for (py::ssize_t s : shape) size *= s;
  return py::array(numpy().attr("arange")(size).attr("__truediv__")(8.0).attr("__sub__")(3.0).attr("reshape")(
      py::tuple(py::cast(shape))));
}

// Every layout x dtype x read-only flag of `values`, as layouts.arrange makes them.
std::vector<py::array> arranged(const py::array& v, const py::object& layout_names, const py::object& dtypes) {
  std::vector<py::array> out;
  for (const auto& layout : layout_names)
    for (const auto& dtype : dtypes)
      for (bool readonly : {false, true}) out.emplace_back(layouts().attr("arrange")(v, layout, dtype, readonly));
  return out;
}

std::string describe(const py::array& a) {
  return py::str("{} strides {} dtype {}").format(a.attr("shape"), a.attr("strides"), a.dtype()).cast<std::string>();
}

// Entry (i, j) of the C-order float64 copy of a (rows x cols, frames stacked).
double expected(const py::array& copy, Eigen::Index i, Eigen::Index j, Eigen::Index cols) {
  return static_cast<const double*>(copy.data())[i * cols + j];
}

void check_read(const py::array& a, const Input& in) {
  INFO(describe(a));
  const py::array copy(layouts().attr("contiguous")(a));
  const Eigen::Index cols = in.map.cols();
  REQUIRE(in.map.rows() * cols == copy.size());
  const Eigen::Ref<const Eigen::MatrixXd> ref(in.map);  // as the libraries take it
  const Eigen::Ref<const Eigen::MatrixXd, 0, Stride> strided(in.map);
  for (Eigen::Index i = 0; i < in.map.rows(); ++i)
    for (Eigen::Index j = 0; j < cols; ++j) {
      REQUIRE(ref(i, j) == expected(copy, i, j, cols));
      REQUIRE(strided(i, j) == expected(copy, i, j, cols));
    }
}

}  // namespace

TEST_CASE("python arrays: every float layout is read in full through Eigen", "[python]") {
  const py::module_ l = layouts();
  for (const auto& shape : {std::vector<py::ssize_t>{7, 3}, {1, 3}, {5, 1}, {0, 3}})
    for (const py::array& a : arranged(values(shape), l.attr("LAYOUTS"), l.attr("FLOATS")))
      check_read(a, float_matrix(a, "A", {}, false));
  for (const auto& shape : {std::vector<py::ssize_t>{3, 7, 3}, {1, 7, 3}, {4, 1, 3}, {0, 7, 3}})
    for (const py::array& a : arranged(values(shape), l.attr("LAYOUTS"), l.attr("FLOATS"))) {
      Frames frames;
      const Input in = float_batch(a, "A", {}, frames, false);
      CHECK(frames.batch);
      CHECK(frames.count == shape[0]);
      check_read(a, in);
    }
}

TEST_CASE("python arrays: every index layout is read in full", "[python]") {
  const py::module_ l = layouts();
  const py::array v(numpy().attr("arange")(24).attr("reshape")(8, 3));
  for (const py::array& a : arranged(v, l.attr("LAYOUTS"), l.attr("INTEGERS"))) {
    INFO(describe(a));
    const Eigen::MatrixXi m = index_matrix(a, "T");
    const py::array copy(l.attr("contiguous")(a));
    for (Eigen::Index i = 0; i < m.rows(); ++i)
      for (Eigen::Index j = 0; j < m.cols(); ++j)
        REQUIRE(m(i, j) == static_cast<const std::int64_t*>(copy.data())[i * 3 + j]);
  }
}

TEST_CASE("python arrays: outputs of every writable layout hold what their map received", "[python]") {
  const py::module_ l = layouts();
  for (const Frames frames : {Frames{}, Frames{3, true}, Frames{0, true}})
    for (const char* dtype : {"<f8", ">f8", "<f4", ">f4"})
      for (const auto& layout : l.attr("WRITABLE")) {
        std::vector<py::ssize_t> shape{6, 3};
        if (frames.batch) shape.insert(shape.begin(), frames.count);
        const py::array out(l.attr("arrange")(numpy().attr("full")(py::tuple(py::cast(shape)), NAN), layout, dtype));
        INFO(describe(out));
        const bool single = dtype[2] == '4';
        py::array result;
        if (single) {
          Output32 o = float32_output(out, "out", 6, 3, frames);
          for (Eigen::Index i = 0; i < o.map.rows(); ++i)
            for (Eigen::Index j = 0; j < 3; ++j) o.map(i, j) = static_cast<float>(i * 3 + j) / 8.0f - 3.0f;
          result = o.finish();
        } else {
          Output o = float_output(out, "out", 6, 3, frames);
          for (Eigen::Index i = 0; i < o.map.rows(); ++i)
            for (Eigen::Index j = 0; j < 3; ++j) o.map(i, j) = static_cast<double>(i * 3 + j) / 8.0 - 3.0;
          result = o.finish();
        }
        REQUIRE(result.is(out));
        REQUIRE(numpy().attr("array_equal")(out, values(shape)).cast<bool>());
      }
}

TEST_CASE("python arrays: outputs that cannot be written are refused before writing", "[python]") {
  const py::object np = numpy();
  const py::object as_strided = py::module_::import("numpy.lib.stride_tricks").attr("as_strided");
  const py::array memory(np.attr("zeros")(40));
  auto refused = [&](const py::object& out, const char* what) {
    INFO(what);
    REQUIRE_THROWS_WITH(float_output(out, "out", 6, 3), Catch::Contains(what));
    REQUIRE(!np.attr("any")(memory).cast<bool>());
  };
  refused(as_strided(memory, py::make_tuple(6, 3), py::make_tuple(0, 8)), "overlaps itself");
  refused(as_strided(memory, py::make_tuple(6, 3), py::make_tuple(8, 8)), "overlaps itself");
  refused(as_strided(memory, py::make_tuple(6, 3), py::make_tuple(8, 0)), "overlaps itself");
  refused(np.attr("broadcast_to")(memory[py::slice(0, 3, 1)], py::make_tuple(6, 3)), "read-only");
  refused(memory[py::slice(0, 18, 1)].attr("reshape")(3, 6), "must have shape (6, 3), got (3, 6)");
  refused(memory.attr("view")("int64")[py::slice(0, 18, 1)].attr("reshape")(6, 3), "must be a float64 array");
  refused(py::list(), "must be a numpy array");
  const py::array m32(np.attr("zeros")(40, "float32"));
  REQUIRE_THROWS_WITH(float32_output(as_strided(m32, py::make_tuple(6, 3), py::make_tuple(0, 4)), "out", 6, 3),
                      Catch::Contains("overlaps itself"));
}

TEST_CASE("python arrays: outputs sharing memory with an input are refused, interleaved ones taken", "[python]") {
  const py::array buffer(numpy().attr("zeros")(py::make_tuple(6, 6)));
  const py::array left(buffer[py::make_tuple(py::slice(0, 6, 1), py::slice(0, 3, 1))]);
  const py::array right(buffer[py::make_tuple(py::slice(0, 6, 1), py::slice(3, 6, 1))]);
  const Output a = float_output(left, "out", 6, 3), b = float_output(right, "normals_out", 6, 3);
  check_disjoint(a, b);  // interleaved columns: no element shared
  const Input x = float_matrix(buffer[py::make_tuple(py::slice(2, 6, 1), py::slice(1, 4, 1))], "X");
  REQUIRE_THROWS_WITH(check_disjoint(a, {&x}), "out shares memory with X");
  REQUIRE_THROWS_WITH(check_disjoint(b, {&x}), "normals_out shares memory with X");
}
