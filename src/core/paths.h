// Finding the files that ship with the project (weights/, scripts/) from wherever a tool is started.
#pragma once
#include <string>

namespace isplat {

// `path` itself when it is absolute or exists relative to the working directory; otherwise the first
// `<dir>/<path>` that exists for dir = the running executable's folder and its parents (so build/tool
// finds the checkout's weights/ from any working directory); otherwise `path` unchanged.
std::string resolve_shipped_path(const std::string& path);

// A name from a config (a dataset, a method) made safe as one file or folder name: letters, digits, '-'
// and '_' stay, anything else (separators, dots, "..") becomes '_'. Outputs never land outside their folder.
std::string safe_name(const std::string& name);

// Fails, naming `path`, unless it is a regular file (after following links): a folder, a device such as /dev/zero
// (which never ends), a FIFO (which blocks), a socket, a symbolic link loop or a missing file. `kind` names what
// was expected in the message ("file", "JSON file").
void require_regular_file(const std::string& path, const char* kind = "file");

}  // namespace isplat
