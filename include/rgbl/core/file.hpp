#pragma once
// Writing a file so that a reader never sees half of it: every writer in rgbl goes through here.

#include <filesystem>
#include <fstream>
#include <functional>

namespace rgbl {

// Calls write(stream) on a temporary file next to `file` (binary mode), then renames it into place;
// on failure removes the temporary and throws Error naming `file`.
void write_atomically(const std::filesystem::path& file, const std::function<void(std::ofstream&)>& write);

}  // namespace rgbl
