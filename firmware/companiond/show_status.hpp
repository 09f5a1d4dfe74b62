#pragma once
// `companiond --show-status FILE`: the machine-readable status written by a running daemon
// (--status-file), printed for a person. Exit code 0, or 1 when the file is missing/invalid.
#include <string>

namespace companiond {
int show_status(const std::string& path);
}
