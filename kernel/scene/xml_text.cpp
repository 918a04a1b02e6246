#include "limber/kernel/scene/xml_text.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>
#include <system_error>

namespace limber::xml {

std::vector<std::size_t> line_starts(std::string_view text) {
  std::vector<std::size_t> starts{0};
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') starts.push_back(i + 1);
  }
  return starts;
}

int line_of(std::span<const std::size_t> starts, std::ptrdiff_t offset) {
  if (offset < 0) return 0;
  auto after = std::upper_bound(starts.begin(), starts.end(), static_cast<std::size_t>(offset));
  return static_cast<int>(after - starts.begin());
}

std::vector<std::string_view> words(std::string_view text) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (i < text.size()) {
    while (i < text.size() && space(text[i])) ++i;
    std::size_t start = i;
    while (i < text.size() && !space(text[i])) ++i;
    if (i > start) out.push_back(text.substr(start, i - start));
  }
  return out;
}

std::optional<double> parse_double(std::string_view word) {
  if (!word.empty() && word.front() == '+') word.remove_prefix(1);
  double value = 0;
  auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
  if (error != std::errc{} || end != word.data() + word.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<std::size_t> invalid_utf8(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto lead = static_cast<unsigned char>(text[i]);
    if (lead < 0x80) {
      ++i;
      continue;
    }
    std::size_t length = 0;
    char32_t code = 0, least = 0;  // least: the smallest code point of this length (shorter is overlong)
    if ((lead & 0xE0) == 0xC0) length = 2, code = lead & 0x1F, least = 0x80;
    else if ((lead & 0xF0) == 0xE0) length = 3, code = lead & 0x0F, least = 0x800;
    else if ((lead & 0xF8) == 0xF0) length = 4, code = lead & 0x07, least = 0x10000;
    else return i;  // a continuation byte or 0xF8..0xFF cannot begin a sequence
    if (text.size() - i < length) return i;
    for (std::size_t k = 1; k < length; ++k) {
      const auto next = static_cast<unsigned char>(text[i + k]);
      if ((next & 0xC0) != 0x80) return i;
      code = (code << 6) | (next & 0x3F);
    }
    if (code < least || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return i;
    i += length;
  }
  return std::nullopt;
}

namespace {

// `node` or the first element after it among its siblings; empty when there is none.
pugi::xml_node element_from(pugi::xml_node node) {
  while (node && node.type() != pugi::node_element) node = node.next_sibling();
  return node;
}

std::string hex_byte(char byte) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  const auto value = static_cast<unsigned char>(byte);
  return {'0', 'x', kDigits[value >> 4], kDigits[value & 15]};
}

// The problem with `text` (a name or a value) when it is not UTF-8.
std::optional<std::string> encoding_problem(std::string_view text, std::string_view of) {
  const auto bad = invalid_utf8(text);
  if (!bad) return std::nullopt;
  return "not valid UTF-8 (byte " + hex_byte(text[*bad]) + " at byte " + std::to_string(*bad + 1) + " of the " + std::string(of) +
         "): limber reads XML files as UTF-8; save the file as UTF-8";
}

// One element's own checks: its name and its attributes' encoding, its depth.
std::optional<TreeProblem> check_element(pugi::xml_node element, int depth, int max_depth) {
  const std::string name = element.name();
  if (auto problem = encoding_problem(name, "name")) return TreeProblem{element, "an element's name", *problem};
  for (pugi::xml_attribute attribute : element.attributes()) {
    const std::string attribute_name = attribute.name();
    if (auto problem = encoding_problem(attribute_name, "name")) return TreeProblem{element, "<" + name + ">: an attribute's name", *problem};
    if (auto problem = encoding_problem(attribute.value(), "value")) return TreeProblem{element, "<" + name + " " + attribute_name + ">", *problem};
  }
  if (depth > max_depth) {
    std::string what = "<" + name;
    if (pugi::xml_attribute named = element.attribute("name")) what.append(" name='").append(named.value()).append("'");
    return TreeProblem{element, what + ">",
                       "nested more than " + std::to_string(max_depth) +
                           " elements deep (the root element the first): no model needs so deep a tree"};
  }
  return std::nullopt;
}

}  // namespace

std::optional<TreeProblem> check_tree(const pugi::xml_document& tree, int max_depth) {
  pugi::xml_node element = tree.document_element();
  int depth = 1;
  while (element) {
    if (auto problem = check_element(element, depth, max_depth)) return problem;
    if (pugi::xml_node child = element_from(element.first_child())) {
      element = child, ++depth;
      continue;
    }
    // Up until an element has a next sibling; the root has none.
    for (;;) {
      if (depth == 1) return std::nullopt;
      if (pugi::xml_node sibling = element_from(element.next_sibling())) {
        element = sibling;
        break;
      }
      element = element.parent(), --depth;
    }
  }
  return std::nullopt;
}

}  // namespace limber::xml
