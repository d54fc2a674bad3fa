#include "core/binary_file.hpp"

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace kodawari::core {

Result<std::vector<unsigned char>> read_binary_file(const std::string& path) {
    std::error_code ec;
    // An input file that is missing or cannot be opened is bad input (the command line's
    // exit 2); a read that fails half way is an I/O failure.
    if (std::filesystem::is_directory(path, ec)) return make_error(Error::Kind::InvalidInput, path + ": cannot read: is a directory");
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (f == nullptr) return make_error(Error::Kind::InvalidInput, path + ": cannot open: " + std::strerror(errno));
    std::vector<unsigned char> bytes;
    std::array<unsigned char, 65536> block{};
    for (;;) {
        const std::size_t n = std::fread(block.data(), 1, block.size(), f);
        bytes.insert(bytes.end(), block.begin(), block.begin() + static_cast<std::ptrdiff_t>(n));
        if (n < block.size()) break;
    }
    const bool failed = std::ferror(f) != 0;
    std::fclose(f);
    if (failed) return make_error(Error::Kind::Io, path + ": read error");
    return bytes;
}

}  // namespace kodawari::core
