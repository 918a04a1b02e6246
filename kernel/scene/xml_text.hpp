// What the XML model readers (MJCF: mjcf_reader.cpp; URDF: urdf.cpp) share about the text they
// parse with pugixml: the line an element starts on, from its offset (pugixml keeps no line
// numbers: xml_node::offset_debug() is the element's offset in the parsed buffer), and the
// strict reading of numbers in attribute values. Internal to kernel/scene.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
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

}  // namespace limber::xml
