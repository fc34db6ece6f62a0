#include "rgbl/core/file.hpp"

#include "rgbl/core/error.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <system_error>

namespace rgbl {

void write_atomically(const std::filesystem::path& file, const std::function<void(std::ofstream&)>& write) {
  auto tmp = file;
  tmp += ".part";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(fmt::format("{}: cannot open for writing", file.string()));
    write(out);
    out.flush();
    if (!out) {
      out.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw Error(fmt::format("{}: write failed (disk full?)", file.string()));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw Error(fmt::format("{}: cannot move the finished file into place", file.string()));
  }
}

TemporaryFolder::TemporaryFolder(const std::string& prefix) {
  std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) throw Error(fmt::format("{}: cannot create a temporary folder", pattern));
  path_ = pattern;
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

namespace {

// "missing", "cannot read: permission denied", ... for an errno from stat/open.
std::string describe_errno(int error) {
  if (error == ENOENT || error == ENOTDIR) return "missing";
  if (error == EACCES || error == EPERM) return "cannot read: permission denied";
  return fmt::format("cannot read: {}", std::strerror(error));
}

}  // namespace

void require_input_file(const std::filesystem::path& file, std::string_view what) {
  struct stat info {};
  if (::stat(file.c_str(), &info) != 0) {
    throw ParseError(file, 0, fmt::format("{} (expected {})", describe_errno(errno), what));
  }
  if (S_ISDIR(info.st_mode)) throw ParseError(file, 0, fmt::format("is a directory (expected {})", what));
  if (!S_ISREG(info.st_mode)) {
    throw ParseError(file, 0,
                     fmt::format("is not a regular file (a FIFO, socket or device, which could block reading; "
                                 "expected {})",
                                 what));
  }
  // stat does not tell whether this process may read it; opening does (and cannot block: a regular file)
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw ParseError(file, 0, fmt::format("{} (expected {})", describe_errno(errno), what));
  ::close(fd);
}

void require_input_folder(const std::filesystem::path& dir, std::string_view what) {
  struct stat info {};
  if (::stat(dir.c_str(), &info) != 0) {
    throw ParseError(dir, 0, fmt::format("not a folder: {} (expected {})", describe_errno(errno), what));
  }
  if (!S_ISDIR(info.st_mode)) throw ParseError(dir, 0, fmt::format("not a folder (expected {})", what));
  DIR* listing = ::opendir(dir.c_str());
  if (listing == nullptr) throw ParseError(dir, 0, fmt::format("{} (expected {})", describe_errno(errno), what));
  ::closedir(listing);
}

std::ifstream open_input_file(const std::filesystem::path& file, std::string_view what, bool binary) {
  require_input_file(file, what);
  std::ifstream in(file, binary ? std::ios::in | std::ios::binary : std::ios::in);
  if (!in) throw ParseError(file, 0, fmt::format("cannot open the file (expected {})", what));
  return in;
}

void require_image_file(const std::filesystem::path& file, std::string_view what) {
  auto in = open_input_file(file, what, true);
  // PNG: 8-byte signature, then the IHDR chunk (length, "IHDR", width and height big-endian)
  std::array<unsigned char, 24> header{};
  in.read(reinterpret_cast<char*>(header.data()), header.size());  // NOLINT
  static constexpr std::array<unsigned char, 8> kSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (in.gcount() != static_cast<std::streamsize>(header.size()) ||
      !std::equal(kSignature.begin(), kSignature.end(), header.begin()) ||
      std::string_view(reinterpret_cast<const char*>(header.data()) + 12, 4) != "IHDR") {  // NOLINT
    return;  // not a PNG (or a broken one): the decoder says what is wrong
  }
  const auto be32 = [&](std::size_t at) {
    return (std::uint64_t{header[at]} << 24) | (std::uint64_t{header[at + 1]} << 16) |
           (std::uint64_t{header[at + 2]} << 8) | std::uint64_t{header[at + 3]};
  };
  const std::uint64_t width = be32(16), height = be32(20);
  if (width * height > kMaxImagePixels) {
    throw ParseError(file, 0,
                     fmt::format("image is {}x{} ({:.0f} megapixels), more than rgbl reads ({} megapixels; expected {})",
                                 width, height, static_cast<double>(width * height) / 1e6, kMaxImagePixels / 1'000'000,
                                 what));
  }
}

}  // namespace rgbl
