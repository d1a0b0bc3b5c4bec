// Text from files (archive metadata, robot names, configs) made safe to print on a terminal.
// A byte string read from an archive may hold ESC, OSC or CR sequences that would move the cursor,
// rewrite earlier lines or set the window title; human output shows them escaped instead.
// Machine output (--json) needs none of this: the JSON writer escapes control characters itself.
#pragma once

#include <string>
#include <string_view>

namespace softevo {

enum class Newlines { escape, keep };

// `text` with every control character written as a visible escape: C0 controls and DEL as \xNN
// (\n kept when `newlines` is keep, for multi-line text such as a config), the UTF-8 encoded C1
// controls U+0080..U+009F (which many terminals obey like ESC [) as \u00NN, and every byte that
// is not part of well-formed UTF-8 as \xNN. Printable ASCII and well-formed UTF-8 pass unchanged.
std::string printable(std::string_view text, Newlines newlines = Newlines::escape);

}  // namespace softevo
