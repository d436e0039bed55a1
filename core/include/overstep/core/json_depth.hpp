#pragma once
/// \file
/// The nesting depth of JSON text, counted without parsing it (nlohmann-json parses recursively:
/// 60,000 nested brackets overflowed the stack, issue 20). Every reader of a JSON file asks it
/// first and refuses text nested deeper than it can hold.

#include <string>

namespace overstep::core {

/// Deepest nesting of arrays and objects in `text` (brackets inside strings do not count); stops
/// counting once past `cap` (then returns cap + 1).
int jsonDepth(const std::string& text, int cap);

}  // namespace overstep::core
