#include <mbi/pipeline/method.hpp>

namespace mbi::pipeline {

const char* method_name(Method m) {
  switch (m) {
    case Method::BI: return "bi";
    case Method::ModifiedBI: return "modified-bi";
    case Method::Phong: return "phong";
  }
  return "?";
}

std::optional<Method> parse_method(std::string_view name) {
  for (Method m : all_methods())
    if (name == method_name(m)) return m;
  return std::nullopt;
}

const std::vector<Method>& all_methods() {
  static const std::vector<Method> methods{Method::BI, Method::ModifiedBI, Method::Phong};
  return methods;
}

const char* method_names() { return "bi, modified-bi, phong"; }

bool needs_solve(Method m) { return m == Method::ModifiedBI; }

bool needs_phong(Method m) { return m == Method::Phong; }

}  // namespace mbi::pipeline
