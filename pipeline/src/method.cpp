#include <mbi/pipeline/method.hpp>

#include <string>

namespace mbi::pipeline {

const char* method_name(Method m) { return kMethodNames.name(m); }

std::optional<Method> parse_method(std::string_view name) { return kMethodNames.find(name); }

const std::vector<Method>& all_methods() {
  static const std::vector<Method> methods = kMethodNames.values();
  return methods;
}

const char* method_names() {
  static const std::string names = kMethodNames.joined();
  return names.c_str();
}

bool needs_solve(Method m) { return m == Method::ModifiedBI; }

bool needs_phong(Method m) { return m == Method::Phong; }

}  // namespace mbi::pipeline
