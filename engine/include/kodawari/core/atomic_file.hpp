#pragma once
/// @file
/// Output files are written to a temporary file beside the target and renamed over it
/// when complete, so a failure never leaves a half-written file.

#include <cstdint>
#include <cstdio>
#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari {

/// A file being written. commit() renames it into place; destruction without commit()
/// removes the temporary file.
class KODAWARI_API AtomicFile {
public:
    /// Opens a file for binary writing that has no name until commit() (O_TMPFILE in
    /// `path`'s directory; where the file system cannot, `<path>.tmp-<pid>`). A character
    /// device or a FIFO at `path` (/dev/null, /dev/stdout) is written directly instead,
    /// never replaced; any other file there that is not a regular file is an error.
    [[nodiscard]] static Result<AtomicFile> open(const std::string& path);

    AtomicFile(AtomicFile&& other) noexcept;
    AtomicFile& operator=(AtomicFile&& other) noexcept;
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;
    ~AtomicFile();

    /// Appends bytes; failures are remembered and reported by commit().
    void write(const void* data, std::size_t size);
    void write(const std::string& text) { write(text.data(), text.size()); }
    /// Where the next write() goes: the bytes written and skipped so far.
    [[nodiscard]] std::uint64_t position() const;
    /// Leaves `size` bytes for another process to write (share()) and goes on after them.
    void skip(std::uint64_t size);

    /// Gives the file a name that other processes can open to write into it before
    /// commit() (the ranks of a distributed bake, on a file system they share), flushes
    /// what was written, and returns that name. A device or a pipe cannot be shared (Io).
    [[nodiscard]] Result<std::string> share();

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
    int error_ = 0;          // errno of the first failed write
    int slot_ = -1;          // its entry among the temporaries removed on a signal
    bool unnamed_ = false;   // O_TMPFILE: no name until commit()
    bool direct_ = false;    // a device or a FIFO, written in place
};

/// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove the temporary file of
/// every AtomicFile still open in the process (up to 64 at once) and then end it as the
/// signal would have, so that an interrupted bake leaves nothing behind (its spilled keys
/// are unlinked from the start). A signal the process was started ignoring stays
/// ignored (nohup). For programs: a library does not install handlers on its
/// own; the `kodawari` command calls this first thing.
KODAWARI_API void remove_temporary_files_on_signals();

/// Whether two paths name one file: the same file on disk (links included) when both
/// exist, else the same absolute path once normalized. For refusing an output that is
/// one of a command's inputs (Scene::reads).
[[nodiscard]] KODAWARI_API bool same_file(const std::string& a, const std::string& b);

}  // namespace kodawari
