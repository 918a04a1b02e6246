// The MJCF reader's files: parsing with pugixml, lines from element offsets (xml_text.hpp),
// <include> splicing, attribute checks and typed attribute reading, the notes.
#include <algorithm>
#include <charconv>
#include <cmath>

#include "limber/kernel/scene/input_file.hpp"
#include "limber/kernel/scene/mjcf_reader.hpp"
#include "limber/kernel/scene/scene_file.hpp"  // the caps: kMaxModelFileBytes, kMaxXmlDepth
#include "limber/kernel/scene/xml_text.hpp"

namespace limber::mjcf::detail {

namespace {

using xml::parse_double;
using xml::words;

int line_of(const Buffer& buffer, std::ptrdiff_t offset) { return xml::line_of(buffer.line_starts, offset); }

}  // namespace

std::string tag(const Node& element, std::string_view attribute) {
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "<" + std::string.
  std::string out(1, '<');
  out.append(element.name());
  if (!attribute.empty()) out.append(1, ' ').append(attribute);
  out.append(1, '>');
  return out;
}

Reader::Reader(const std::filesystem::path& main_file)
    : main_file_(main_file), directory_(main_file.parent_path()) {}

const Buffer& Reader::parse(std::string file, std::string text) {
  Buffer& buffer = buffers_.emplace_back();
  buffer.file = std::move(file);
  buffer.text = std::move(text);
  buffer.line_starts = xml::line_starts(buffer.text);
  bytes_ += buffer.text.size();
  pugi::xml_parse_result result =
      buffer.tree.load_buffer(buffer.text.data(), buffer.text.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!result) {
    throw ModelError(buffer.file + ":" + std::to_string(line_of(buffer, result.offset)) +
                     ": XML error: " + result.description());
  }
  if (!buffer.tree.document_element()) throw ModelError(buffer.file + ": XML error: no root element");
  if (auto problem = xml::check_tree(buffer.tree, kMaxXmlDepth)) fail(Node{problem->node, &buffer}, problem->what, problem->problem);
  return buffer;
}

Node Reader::parse_main(std::string_view xml) {
  std::error_code error;
  std::string key = std::filesystem::weakly_canonical(main_file_, error).string();
  included_.insert(error ? main_file_.string() : key);
  const Buffer& buffer = parse(main_file_.string(), std::string(xml));
  Node root{buffer.tree.document_element(), &buffer};
  if (root.name() != "mujoco") fail(root, tag(root), "not an MJCF file: its root element must be <mujoco>");
  return root;
}

const Buffer& Reader::include(const Node& element) {
  check_attributes(element, {"file"});
  refuse_children(element);
  auto name = text(element, "file");
  if (!name || name->empty()) fail(element, tag(element, "file"), "missing: the file to include");
  const std::filesystem::path path = directory_ / std::filesystem::path(std::string(*name));
  std::error_code error;
  std::string key = std::filesystem::weakly_canonical(path, error).string();
  if (error) key = path.string();
  if (!included_.insert(key).second) {
    fail(element, tag(element, "file"),
         "'" + path.string() + "' is already included (a file may be read once: twice, or a cycle)");
  }
  std::string content;
  try {
    content = scene_input::read_file(path, scene_input::FileKind::model, bytes_);
  } catch (const ModelError& problem) {
    fail(element, tag(element, "file"), problem.what());
  }
  return parse(path.string(), std::move(content));
}

std::vector<Node> Reader::children(const Node& element) {
  std::vector<Node> out;
  for (pugi::xml_node child = element.xml.first_child(); child; child = child.next_sibling()) {
    if (child.type() != pugi::node_element) continue;
    Node node{child, element.buffer};
    if (node.name() != "include") {
      out.push_back(node);
      continue;
    }
    // An include at the root of an included file recurses: its depth is bounded as elements' are.
    if (include_depth_ >= kMaxXmlDepth) {
      fail(node, tag(node), "includes nested more than " + std::to_string(kMaxXmlDepth) + " deep (through the files' roots)");
    }
    const Buffer& included = include(node);
    Node root{included.tree.document_element(), &included};
    ++include_depth_;
    for (Node& spliced : children(root)) out.push_back(spliced);
    --include_depth_;
  }
  return out;
}

Source Reader::source(const Node& element) const {
  return {element.buffer->file, line_of(*element.buffer, element.xml.offset_debug())};
}

void Reader::fail(const Node& element, std::string_view what, std::string_view problem) const {
  const Source at = source(element);
  throw ModelError(at.file + ":" + std::to_string(at.line) + ": " + std::string(what) + ": " + std::string(problem));
}

void Reader::note(const Node& element, std::string_view what, std::string_view reason) {
  const Source at = source(element);
  if (!noted_.insert(at.file + "\n" + std::string(what)).second) return;
  notes_.push_back(at.file + ":" + std::to_string(at.line) + ": " + std::string(what) + ": ignored: " +
                   std::string(reason));
}

void Reader::check_attributes(const Node& element, std::initializer_list<std::string_view> read,
                              std::initializer_list<Ignored> ignored) {
  for (pugi::xml_attribute attribute : element.xml.attributes()) {
    const std::string_view name = attribute.name();
    if (std::find(read.begin(), read.end(), name) != read.end()) continue;
    auto drop = std::find_if(ignored.begin(), ignored.end(), [&](const Ignored& i) { return i.attribute == name; });
    if (drop == ignored.end()) {
      fail(element, tag(element, name), "not supported: unknown attribute (MuJoCo 2.2.2's schema has no such attribute here)");
    }
    note(element, tag(element, name), drop->reason);
  }
}

void Reader::refuse_children(const Node& element) {
  for (pugi::xml_node child = element.xml.first_child(); child; child = child.next_sibling()) {
    if (child.type() != pugi::node_element) continue;
    Node node{child, element.buffer};
    fail(node, tag(node), "not supported: unknown element (not a child of " + tag(element) + " in MuJoCo's schema)");
  }
}

std::optional<std::string_view> Reader::text(const Node& element, const char* attribute) const {
  pugi::xml_attribute found = element.xml.attribute(attribute);
  if (!found) return std::nullopt;
  return std::string_view(found.value());
}

bool Reader::numbers(const Node& element, const char* attribute, std::span<double> values, bool exact) const {
  auto written = text(element, attribute);
  if (!written) return false;
  const std::vector<std::string_view> parts = words(*written);
  std::vector<double> parsed;
  for (std::string_view part : parts) {
    auto value = parse_double(part);
    if (!value) break;
    parsed.push_back(*value);
  }
  const std::size_t n = values.size();
  const bool count_ok = exact ? parts.size() == n : !parts.empty() && parts.size() <= n;
  if (!count_ok || parsed.size() != parts.size()) {
    std::string expected = exact || n == 1 ? std::to_string(n) : "1 to " + std::to_string(n);
    expected += n == 1 ? " number" : " numbers";
    fail(element, tag(element, attribute), "expected " + expected + ", got '" + std::string(*written) + "'");
  }
  std::copy(parsed.begin(), parsed.end(), values.begin());
  return true;
}

std::optional<double> Reader::number(const Node& element, const char* attribute) const {
  double value = 0;
  if (!numbers(element, attribute, std::span<double>(&value, 1), true)) return std::nullopt;
  return value;
}

std::optional<int> Reader::integer(const Node& element, const char* attribute) const {
  auto written = text(element, attribute);
  if (!written) return std::nullopt;
  const std::vector<std::string_view> parts = words(*written);
  int value = 0;
  if (parts.size() == 1) {
    std::string_view word = parts[0];
    auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (error == std::errc{} && end == word.data() + word.size()) return value;
  }
  fail(element, tag(element, attribute), "expected an integer, got '" + std::string(*written) + "'");
}

std::optional<bool> Reader::boolean(const Node& element, const char* attribute) const {
  auto index = keyword(element, attribute, {"false", "true"});
  if (!index) return std::nullopt;
  return *index == 1;
}

std::optional<int> Reader::keyword(const Node& element, const char* attribute,
                                   std::initializer_list<std::string_view> choices) const {
  auto written = text(element, attribute);
  if (!written) return std::nullopt;
  int index = 0;
  std::string list;
  for (std::string_view choice : choices) {
    if (choice == *written) return index;
    list += (index ? ", " : "") + std::string(choice);
    ++index;
  }
  fail(element, tag(element, attribute), "expected one of " + list + ", got '" + std::string(*written) + "'");
}

int Context::element_class(const Node& element, int inherited) const {
  auto name = reader.text(element, "class");
  if (!name) return inherited;
  auto found = class_index.find(std::string(*name));
  if (found == class_index.end()) {
    reader.fail(element, tag(element, "class"), "unknown default class '" + std::string(*name) + "'");
  }
  return found->second;
}

}  // namespace limber::mjcf::detail
