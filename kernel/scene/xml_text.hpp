// What the XML model readers (MJCF: mjcf_reader.cpp; URDF: urdf.cpp) share about the text they
// parse with pugixml: the line an element starts on, from its offset (pugixml keeps no line
// numbers: xml_node::offset_debug() is the element's offset in the parsed buffer), and the
// strict reading of numbers in attribute values, and the checks every parsed file passes before
// it is read: its nesting depth and its text's encoding. Internal to kernel/scene: it includes
// pugixml, which limber keeps private, so no public header may include this one.
#pragma once

#include <cstddef>
#include <optional>
#include <pugixml.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber::xml {

/// The offset of each line's first character in `text` (the first line: 0).
std::vector<std::size_t> line_starts(std::string_view text);

/// The 1-based line holding `offset`, given line_starts() of the text; 0 for a negative offset
/// (pugixml's "unknown": a node made or edited after parsing).
int line_of(std::span<const std::size_t> starts, std::ptrdiff_t offset);

/// `text` split on XML whitespace (space, tab, CR, LF).
std::vector<std::string_view> words(std::string_view text);

/// A whole word as a finite double ("+1", ".5", "1e-3"); nullopt for anything else (trailing
/// characters, "nan", "inf", an overflow), as MuJoCo's strtod-based reading refuses.
std::optional<double> parse_double(std::string_view word);

/// The offset of the first byte of `text` that does not begin a valid UTF-8 sequence, or that
/// begins one cut short; nullopt when all of `text` is UTF-8. Overlong forms, surrogates
/// (U+D800..U+DFFF) and code points past U+10FFFF are invalid, as RFC 3629 says.
std::optional<std::size_t> invalid_utf8(std::string_view text);

/// Where a parsed file breaks a rule that holds before any element is read: the node (its line
/// comes from its offset), what to name ("<body name='b96'>", "<geom name>") and the problem.
struct TreeProblem {
  pugi::xml_node node;
  std::string what;
  std::string problem;
};

/// Checks every element of `tree` in document order, without recursion (any depth is safe): its
/// name, its attributes' names and values are UTF-8 (limber reads files as UTF-8, and a name
/// must be text: Python reads it as str), and it is nested at most `max_depth` deep (the root
/// element: 1). Text and comments are not read, so not checked. The first problem, or nullopt.
std::optional<TreeProblem> check_tree(const pugi::xml_document& tree, int max_depth);

}  // namespace limber::xml
