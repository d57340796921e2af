#pragma once
// One table of names per enum: how its values are spelled in scene files, on the command line
// and in messages. The table is the only place the names are written; parsers, CLI checks and
// messages all read it.
//
//   inline constexpr auto kMethodNames = mbi::name_table<Method>(
//       {{Method::BI, "bi"}, {Method::ModifiedBI, "modified-bi"}, {Method::Phong, "phong"}});
//   kMethodNames.name(Method::BI)        // "bi"
//   kMethodNames.find("phong")           // Method::Phong (nullopt for an unknown name)
//   kMethodNames.parse(s, "--method")    // or mbi::Error "--method: unknown value ..."
//   kMethodNames.names()                 // {"bi", "modified-bi", "phong"} (CLI::IsMember)
#include <mbi/error.hpp>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mbi {

template <typename E>
struct NameEntry {
  E value;
  const char* name;
};

template <typename E, std::size_t N>
class NameTable {
 public:
  constexpr explicit NameTable(const std::array<NameEntry<E>, N>& entries) : entries_(entries) {}

  /// The name of `value`; "" for a value the table leaves out (a "none" value).
  constexpr const char* name(E value) const {
    for (const NameEntry<E>& e : entries_)
      if (e.value == value) return e.name;
    return "";
  }
  std::optional<E> find(std::string_view name) const {
    for (const NameEntry<E>& e : entries_)
      if (name == e.name) return e.value;
    return std::nullopt;
  }
  /// The value named `name`; else mbi::Error "<what>: <unknown(name)>".
  E parse(std::string_view name, std::string_view what) const {
    if (const std::optional<E> v = find(name)) return *v;
    throw Error(std::string(what) + ": " + unknown(name));
  }
  /// `unknown value "x" (expected one of: a, b, c)`.
  std::string unknown(std::string_view name) const {
    return "unknown value \"" + std::string(name) + "\" (expected one of: " + joined() + ")";
  }
  /// The names in table order.
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const NameEntry<E>& e : entries_) out.emplace_back(e.name);
    return out;
  }
  /// The values in table order.
  std::vector<E> values() const {
    std::vector<E> out;
    for (const NameEntry<E>& e : entries_) out.push_back(e.value);
    return out;
  }
  /// The names joined by ", ".
  std::string joined() const {
    std::string out;
    for (const NameEntry<E>& e : entries_) out += (out.empty() ? "" : ", ") + std::string(e.name);
    return out;
  }

 private:
  std::array<NameEntry<E>, N> entries_;
};

/// A table from a braced list of {value, name}: name_table<Mode>({{Mode::A, "a"}, ...}).
template <typename E, std::size_t N>
constexpr NameTable<E, N> name_table(const NameEntry<E> (&entries)[N]) {
  std::array<NameEntry<E>, N> a{};
  for (std::size_t i = 0; i < N; ++i) a[i] = entries[i];
  return NameTable<E, N>(a);
}

}  // namespace mbi
