#pragma once
// The lab's IDL files as compiled into the binaries.
#include <string>
#include <string_view>

namespace dw::idl {

// The text of one IDL file ("Wrench"), or an empty view.
std::string_view text(std::string_view file);
// One self-contained IDL document for a file: its includes inlined (each once, dependencies
// first) and preprocessor lines removed — MCAP's `omgidl` schema encoding.
std::string resolved(std::string_view file);

}  // namespace dw::idl
