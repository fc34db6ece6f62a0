#include "rgbl/core/file.hpp"

#include "rgbl/core/error.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <random>
#include <string_view>
#include <system_error>
#include <vector>

namespace rgbl {
namespace {

namespace fs = std::filesystem;

std::string errno_text(int error) { return std::generic_category().message(error); }

// Closes the descriptor it owns.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

constexpr std::string_view kTemporarySuffix = ".part";

// Creates (O_EXCL) a file named <prefix>.<random><suffix> in `folder` that no one else uses, mode 0666
// less the umask as for any new file; returns its path, or the errno of the failure.
std::pair<fs::path, int> create_unique(const fs::path& folder, const std::string& prefix, const std::string& suffix) {
  std::random_device random;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const fs::path candidate = folder / fmt::format("{}.{:08x}{}", prefix, random(), suffix);
    const FileDescriptor fd(::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666));
    if (fd.get() >= 0) return {candidate, 0};
    if (errno != EEXIST) return {fs::path(), errno};
  }
  return {fs::path(), EEXIST};
}

// Runs write() on `out` and checks the stream afterwards; throws Error naming `file`.
void write_and_check(const fs::path& file, std::ofstream& out, const std::function<void(std::ofstream&)>& write) {
  errno = 0;
  write(out);
  out.flush();
  if (!out) {
    const int error = errno;
    throw Error(fmt::format("{}: write failed ({})", file.string(), error != 0 ? errno_text(error) : "disk full?"));
  }
}

// Not a regular file (a FIFO, a device, a link to one, a dangling link): written through, as `> file`
// in a shell would, so that the node stays what it is.
void write_through(const fs::path& file, bool fifo, const std::function<void(std::ofstream&)>& write) {
  // a FIFO without a reader would block the open for ever: held open (non-blocking) while the stream
  // opens, it also spares that open the wait
  const FileDescriptor reader_check(fifo ? ::open(file.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC) : -1);
  if (fifo && reader_check.get() < 0) {
    if (errno == ENXIO) {
      throw Error(fmt::format("{}: a FIFO with no reader (start the program that reads it first)", file.string()));
    }
    throw Error(fmt::format("{}: cannot open for writing ({})", file.string(), errno_text(errno)));
  }
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw Error(fmt::format("{}: cannot open for writing ({})", file.string(), errno_text(errno)));
  write_and_check(file, out, write);
}

// A regular file (or a new one): written to a temporary next to it and renamed over it.
void replace(const fs::path& file, const struct stat* existing, const std::function<void(std::ofstream&)>& write) {
  const fs::path folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  const auto [tmp, error] = create_unique(folder, file.filename().string(), std::string(kTemporarySuffix));
  if (tmp.empty()) throw Error(fmt::format("{}: cannot open for writing ({})", file.string(), errno_text(error)));
  try {
    // the replacement keeps the permissions of the file it replaces
    if (existing != nullptr) ::chmod(tmp.c_str(), existing->st_mode & 07777);
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw Error(fmt::format("{}: cannot open for writing ({})", file.string(), errno_text(errno)));
      write_and_check(file, out, write);
      out.close();
      if (!out) throw Error(fmt::format("{}: write failed ({})", file.string(), errno_text(errno)));
    }
    std::error_code ec;
    fs::rename(tmp, file, ec);
    if (ec) {
      throw Error(fmt::format("{}: cannot move the finished file into place ({})", file.string(), ec.message()));
    }
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);  // never a *.part left behind, whatever failed
    throw;
  }
}

}  // namespace

void write_atomically(const fs::path& file, const std::function<void(std::ofstream&)>& write) {
  struct stat target {};
  if (::stat(file.c_str(), &target) == 0) {  // follows links: what `file` finally is
    if (S_ISDIR(target.st_mode)) throw Error(fmt::format("{}: is a folder (expected a file to write)", file.string()));
    if (!S_ISREG(target.st_mode)) return write_through(file, S_ISFIFO(target.st_mode), write);
    struct stat link {};
    if (::lstat(file.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
      // replace the file the link points to and keep the link; a link that does not resolve to that
      // file by path (/proc/self/fd/N of a deleted file) is written through
      std::error_code ec;
      const fs::path resolved = fs::canonical(file, ec);
      struct stat again {};
      if (ec || ::stat(resolved.c_str(), &again) != 0 || again.st_dev != target.st_dev ||
          again.st_ino != target.st_ino) {
        return write_through(file, false, write);
      }
      return replace(resolved, &target, write);
    }
    return replace(file, &target, write);
  }
  struct stat link {};
  if (::lstat(file.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
    return write_through(file, false, write);  // a dangling link: create the file it names
  }
  replace(file, nullptr, write);
}

void write_atomically(const fs::path& file, std::span<const unsigned char> bytes) {
  write_atomically(file, [&](std::ofstream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  });
}

void remove_temporaries_of(const fs::path& file) {
  const fs::path folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  const std::string prefix = file.filename().string() + ".";
  std::vector<fs::path> stale;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() > prefix.size() + kTemporarySuffix.size() && name.starts_with(prefix) &&
        name.ends_with(kTemporarySuffix)) {
      stale.push_back(it->path());
    }
  }
  for (const fs::path& path : stale) fs::remove(path, ec);
}

OutputFolder::OutputFolder(fs::path folder) : path_(std::move(folder)) {
  std::error_code ec;
  fs::create_directories(path_, ec);
  if (ec || !fs::is_directory(path_, ec)) {
    throw Error(fmt::format("{}: cannot create the output folder ({})", path_.string(),
                            ec ? ec.message() : "a file of that name exists"));
  }
  fd_ = ::open(path_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) throw Error(fmt::format("{}: cannot open the output folder ({})", path_.string(), errno_text(errno)));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK) {
      throw Error(fmt::format("{}: another rgbl process is writing into this output folder (wait for it to finish, "
                              "or choose another folder)",
                              path_.string()));
    }
    throw Error(fmt::format("{}: cannot lock the output folder ({})", path_.string(), errno_text(error)));
  }
  // writable: a probe file created and removed (access(2) says yes to root on a read-only mount)
  const auto [probe, error] = create_unique(path_, ".rgbl-write-test", "");
  if (probe.empty()) {
    ::close(fd_);
    fd_ = -1;
    throw Error(fmt::format("{}: cannot write into the output folder ({})", path_.string(), errno_text(error)));
  }
  fs::remove(probe, ec);
}

OutputFolder::~OutputFolder() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

TemporaryFolder::TemporaryFolder(const std::string& prefix) {
  std::string pattern = (fs::temp_directory_path() / (prefix + "_XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) throw Error(fmt::format("{}: cannot create a temporary folder", pattern));
  path_ = pattern;
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ec;
  fs::remove_all(path_, ec);
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
  const auto read = static_cast<std::size_t>(in.gcount());
  const bool png = read >= kSignature.size() && std::equal(kSignature.begin(), kSignature.end(), header.begin());
  const bool jpeg = read >= 3 && header[0] == 0xFF && header[1] == 0xD8 && header[2] == 0xFF;
  // Only PNG and JPEG reach a decoder (rgbl/io/image.hpp): anything else gets this clear message.
  if (!png && !jpeg) {
    throw ParseError(file, 0, fmt::format("not a PNG or JPEG file (by its first bytes; expected {})", what));
  }
  if (!png || read != header.size() ||
      std::string_view(reinterpret_cast<const char*>(header.data()) + 12, 4) != "IHDR") {  // NOLINT
    return;  // a JPEG, or a broken PNG: the decoder says what is wrong
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
