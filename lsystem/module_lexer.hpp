// Internal to lsystem/: reading module names, shared by the string parser and the rule parser.
#pragma once

#include "lsystem/module_string.hpp"
#include "lsystem/text_cursor.hpp"

#include <string>

namespace treelobes::lsystem::detail {

// Characters that are module names on their own (turtle commands and ABOP/cpfg punctuation).
bool is_symbol_char(char c);

// True when a module name starts at the cursor (after skipping spaces).
bool at_module_name(Cursor& cursor);

// Reads one module name at the cursor (spaces skipped first): a declared long name (longest
// match), a letter followed by digits, or one symbol character. Fails with line/column otherwise.
std::string read_module_name(Cursor& cursor, const Alphabet& alphabet);

}  // namespace treelobes::lsystem::detail
