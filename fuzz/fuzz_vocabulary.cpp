// Any bytes as the body of a vocabulary file: the checksum is appended here, so the fuzzer reaches the
// structural checks behind it. Either a vocabulary whose every word lookup stays inside the tree, or a
// ParseError.
#include "rgbl/core/error.hpp"
#include "rgbl/place/vocabulary.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a 64, as the format's trailer
  for (const std::uint8_t b : bytes) {
    h ^= b;
    h *= 0x100000001b3ULL;
  }
  for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<std::uint8_t>(h >> (8 * i)));
  try {
    const rgbl::Vocabulary v = rgbl::Vocabulary::from_bytes(bytes, "fuzz");
    std::vector<rgbl::Descriptor> descriptors(4);
    for (std::size_t i = 0; i < descriptors.size(); ++i) descriptors[i].fill(static_cast<std::uint8_t>(0x55U * i));
    const rgbl::BowVector bow = v.transform(descriptors);
    for (const auto& [word, weight] : bow) {
      if (word >= v.words() || !(weight > 0.0F)) __builtin_trap();
    }
  } catch (const rgbl::ParseError&) {
  }
  return 0;
}
