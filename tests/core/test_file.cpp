// rgbl::write_atomically and rgbl::OutputFolder: no half-written file, no file of another writer, no
// special file replaced by a regular one, no output folder shared by two processes.
#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const fs::path& file, const std::string& text) {
  rgbl::write_atomically(file, [&](std::ofstream& out) { out << text; });
}

std::vector<std::string> names_in(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(folder)) names.push_back(e.path().filename().string());
  return names;
}

}  // namespace

TEST_CASE("write_atomically replaces a regular file whole and keeps its permissions") {
  const rgbl::TemporaryFolder dir;
  const auto file = dir.path() / "a.txt";
  write_text(file, "first");
  ::chmod(file.c_str(), 0640);
  write_text(file, "second");
  CHECK(contents(file) == "second");
  struct stat st {};
  REQUIRE(::stat(file.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0640);
  CHECK(names_in(dir.path()) == std::vector<std::string>{"a.txt"});
}

TEST_CASE("write_atomically leaves no temporary file when the writer throws") {
  const rgbl::TemporaryFolder dir;
  const auto file = dir.path() / "report.json";
  write_text(file, "old");
  CHECK_THROWS_AS(rgbl::write_atomically(file, [](std::ofstream& out) {
                    out << "half";
                    throw std::runtime_error("the writer failed");
                  }),
                  std::runtime_error);
  CHECK(contents(file) == "old");
  CHECK(names_in(dir.path()) == std::vector<std::string>{"report.json"});
}

TEST_CASE("write_atomically writes bytes, and a killed writer's temporaries are removed, nothing else") {
  const rgbl::TemporaryFolder dir;
  const auto file = dir.path() / "map.png";
  const std::vector<unsigned char> bytes = {0x89, 'P', 'N', 'G', 0x00, 0xff};
  rgbl::write_atomically(file, bytes);
  CHECK(contents(file) == std::string(bytes.begin(), bytes.end()));
  // what SIGKILL during a write leaves, next to look-alikes that are not this file's temporaries
  for (const char* name : {"map.png.1a2b3c4d.part", "map.png.part", "other.png.1a2b3c4d.part", "notes.part"}) {
    std::ofstream(dir.path() / name) << "x";
  }
  rgbl::remove_temporaries_of(file);
  auto names = names_in(dir.path());
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{"map.png", "map.png.part", "notes.part", "other.png.1a2b3c4d.part"});
}

TEST_CASE("write_atomically writes through a symbolic link, keeping the link") {
  const rgbl::TemporaryFolder dir;
  fs::create_directories(dir.path() / "real");
  const auto target = dir.path() / "real" / "out.txt";
  write_text(target, "old");
  const auto link = dir.path() / "link.txt";
  fs::create_symlink("real/out.txt", link);
  write_text(link, "new");
  CHECK(fs::is_symlink(fs::symlink_status(link)));
  CHECK(fs::read_symlink(link) == fs::path("real/out.txt"));
  CHECK(contents(target) == "new");
  CHECK(names_in(dir.path() / "real") == std::vector<std::string>{"out.txt"});

  // a dangling link: the file it names is created
  const auto dangling = dir.path() / "dangling.txt";
  fs::create_symlink("real/new.txt", dangling);
  write_text(dangling, "created");
  CHECK(fs::is_symlink(fs::symlink_status(dangling)));
  CHECK(contents(dir.path() / "real" / "new.txt") == "created");
}

TEST_CASE("write_atomically writes into a FIFO instead of replacing it, and refuses one without a reader") {
  const rgbl::TemporaryFolder dir;
  const auto fifo = dir.path() / "fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_THROWS_WITH(write_text(fifo, "nobody reads"), Catch::Contains("a FIFO with no reader"));
  std::string received;
  std::thread reader([&] { received = contents(fifo); });
  // the reader's open blocks until a writer comes; retry until it is there
  for (int attempt = 0;; ++attempt) {
    try {
      write_text(fifo, "through the pipe");
      break;
    } catch (const rgbl::Error&) {
      REQUIRE(attempt < 500);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  reader.join();
  CHECK(received == "through the pipe");
  struct stat st {};
  REQUIRE(::lstat(fifo.c_str(), &st) == 0);
  CHECK(S_ISFIFO(st.st_mode));
  CHECK(names_in(dir.path()) == std::vector<std::string>{"fifo"});
}

TEST_CASE("write_atomically writes into a device node instead of replacing it") {
  const rgbl::TemporaryFolder dir;
  const auto node = dir.path() / "null";
  if (::mknod(node.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0) {
    WARN("cannot create a device node here (not root): checked on /dev/null's behaviour through a link instead");
    fs::create_symlink("/dev/null", node);
  }
  write_text(node, "discarded");
  struct stat st {};
  REQUIRE(::stat(node.c_str(), &st) == 0);
  CHECK(S_ISCHR(st.st_mode));
  CHECK(names_in(dir.path()) == std::vector<std::string>{"null"});
  CHECK_THROWS_WITH(write_text(dir.path(), "x"), Catch::Contains("is a folder"));
}

TEST_CASE("concurrent write_atomically calls on one file never mix their contents") {
  const rgbl::TemporaryFolder dir;
  const auto file = dir.path() / "shared.txt";
  const std::string a(200000, 'a'), b(100000, 'b');
  const auto writer = [&](const std::string& text) {
    for (int i = 0; i < 40; ++i) write_text(file, text);
  };
  std::thread ta(writer, a), tb(writer, b);
  ta.join();
  tb.join();
  const std::string result = contents(file);
  CHECK((result == a || result == b));
  CHECK(names_in(dir.path()) == std::vector<std::string>{"shared.txt"});
}

TEST_CASE("an output folder is created, checked writable and held by one writer at a time") {
  const rgbl::TemporaryFolder dir;
  const auto out = dir.path() / "out";
  {
    const rgbl::OutputFolder first(out);
    CHECK(fs::is_directory(out));
    CHECK(fs::is_empty(out));  // no lock file, no probe left
    CHECK_THROWS_WITH(rgbl::OutputFolder(out), Catch::Contains("another rgbl process is writing into this output folder"));
  }
  CHECK_NOTHROW(rgbl::OutputFolder(out));  // released
  CHECK(fs::is_empty(out));

  // a file in the way
  std::ofstream(dir.path() / "file") << "x";
  CHECK_THROWS_WITH(rgbl::OutputFolder(dir.path() / "file"), Catch::Contains("cannot create the output folder"));
  CHECK_THROWS_WITH(rgbl::OutputFolder(dir.path() / "file" / "sub"), Catch::Contains("cannot create the output folder"));
  if (::geteuid() != 0) {  // root writes into a read-only folder anyway
    fs::create_directories(dir.path() / "ro");
    ::chmod((dir.path() / "ro").c_str(), 0555);
    CHECK_THROWS_WITH(rgbl::OutputFolder(dir.path() / "ro"), Catch::Contains("cannot write into the output folder"));
    ::chmod((dir.path() / "ro").c_str(), 0755);
  }
}
