// ParaView collections (.pvd): the list of files of a time series, read (see read_pvd).
//   <VTKFile type="Collection"><Collection>
//     <DataSet timestep="0.1" group="" part="0" file="frame_0001.vtu"/> ...
#include "io_common.hpp"

#include <pugixml.hpp>

#include <algorithm>
#include <cmath>

namespace mbi::io {

using detail::fail;
using std::filesystem::path;

std::vector<PvdEntry> read_pvd(const path& file) { return parse_pvd(detail::slurp(file), file); }

std::vector<PvdEntry> parse_pvd(std::string_view data, const path& file) {
  data = detail::skip_bom(data);
  detail::LineCounter lines(data);
  pugi::xml_document doc;
  const pugi::xml_parse_result r = doc.load_buffer(data.data(), data.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!r) fail(file, lines.line_of(static_cast<std::size_t>(std::max<std::ptrdiff_t>(r.offset, 0))),
               std::string("not valid XML: ") + r.description());
  auto line = [&](const pugi::xml_node& n) {
    const std::ptrdiff_t at = n.offset_debug();
    return at < 0 ? 0 : lines.line_of(static_cast<std::size_t>(at));
  };
  const pugi::xml_node root = doc.child("VTKFile");
  if (!root) fail(file, 0, "not a ParaView collection (no VTKFile element)");
  const std::string type = root.attribute("type").value();
  if (type != "Collection") fail(file, line(root), "VTKFile of type '" + type.substr(0, 40) + "' (a .pvd is a Collection)");
  const pugi::xml_node collection = root.child("Collection");
  if (!collection) fail(file, line(root), "no Collection element");
  std::vector<PvdEntry> entries;
  for (const pugi::xml_node& ds : collection.children("DataSet")) {
    PvdEntry e;
    e.line = line(ds);
    const std::string name = ds.attribute("file").value();
    if (name.empty()) fail(file, e.line, "DataSet without a file");
    const pugi::xml_attribute part = ds.attribute("part");
    if (part && part.as_int(0) != 0)
      fail(file, e.line, "DataSet of part " + std::string(part.value()).substr(0, 20) +
                             ": collections of several parts per timestep are not read");
    const pugi::xml_attribute t = ds.attribute("timestep");
    e.time = t ? detail::to_double(t.value(), file, e.line, "timestep") : static_cast<double>(entries.size());
    e.file = path(name).is_absolute() ? path(name) : file.parent_path() / name;
    entries.push_back(std::move(e));
  }
  if (entries.empty()) fail(file, line(collection), "the collection names no DataSet");
  std::stable_sort(entries.begin(), entries.end(), [](const PvdEntry& a, const PvdEntry& b) { return a.time < b.time; });
  for (std::size_t k = 1; k < entries.size(); ++k)
    if (entries[k].time == entries[k - 1].time)
      fail(file, entries[k].line, "two DataSets of timestep " + detail::fmt(entries[k].time) + " (lines " +
                                      std::to_string(entries[k - 1].line) + " and " + std::to_string(entries[k].line) + ")");
  return entries;
}

}  // namespace mbi::io
