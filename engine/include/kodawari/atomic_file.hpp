#pragma once
/// @file
/// Output files are written to a temporary file beside the target and renamed over it
/// when complete, so a failure never leaves a half-written file.

#include <cstdio>
#include <string>

#include "kodawari/api.hpp"
#include "result.hpp"

namespace kodawari {

/// A file being written. commit() renames it into place; destruction without commit()
/// removes the temporary file.
class KODAWARI_API AtomicFile {
public:
    /// Opens `<path>.tmp-<pid>` for binary writing.
    [[nodiscard]] static Result<AtomicFile> open(const std::string& path);

    AtomicFile(AtomicFile&& other) noexcept;
    AtomicFile& operator=(AtomicFile&& other) noexcept;
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;
    ~AtomicFile();

    /// Appends bytes; failures are remembered and reported by commit().
    void write(const void* data, std::size_t size);
    void write(const std::string& text) { write(text.data(), text.size()); }

    /// Flushes, syncs and renames over the target.
    [[nodiscard]] Result<void> commit();

    [[nodiscard]] const std::string& path() const { return path_; }

private:
    AtomicFile(std::string path, std::string temp, std::FILE* file) : path_(std::move(path)), temp_(std::move(temp)), file_(file) {}
    void discard();

    std::string path_;
    std::string temp_;
    std::FILE* file_ = nullptr;
    bool failed_ = false;
};

}  // namespace kodawari
