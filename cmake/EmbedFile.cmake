# cmake -DINPUT=<file> -DOUTPUT=<file.cpp> -DSYMBOL=<name> -P EmbedFile.cmake
#
# Writes a C++ source defining `std::span<const std::uint8_t> rgbl::detail::<SYMBOL>()` over the bytes
# of INPUT, so a data file (the shipped vocabulary) is part of the library: no install path to find at
# run time. Run at build time; the output changes only when INPUT does.
file(READ "${INPUT}" hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
# 0x.., per byte, 32 per line
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "((0x[0-9a-f][0-9a-f],){32})" "\\1\n" bytes "${bytes}")
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${INPUT} by cmake/EmbedFile.cmake: do not edit.\n"
  "#include <cstdint>\n#include <span>\n\n"
  "namespace rgbl::detail {\nnamespace {\nconst std::uint8_t kBytes[${size} + 1] = {\n${bytes}\n0};\n}  // namespace\n"
  "std::span<const std::uint8_t> ${SYMBOL}() { return {kBytes, ${size}}; }\n}  // namespace rgbl::detail\n")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUTPUT}.tmp")
