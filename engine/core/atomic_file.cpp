#include "kodawari/core/atomic_file.hpp"

#include <array>
#include <cassert>
#include <cstdint>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace kodawari {

namespace {

// The temporary files open in this process, for remove_temporary_files_on_signals(): a
// signal handler may only unlink() what is already there, so the paths live in fixed
// slots (state kFree -> kFilling -> kReady -> kFree), read by the handler without locks.
constexpr std::size_t kSlots = 64;
constexpr std::size_t kPathBytes = 4096;
enum SlotState : int { kFree = 0, kFilling = 1, kReady = 2 };
struct TempSlot {
    std::atomic<int> state{kFree};
    std::array<char, kPathBytes> path{};
};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler reads the slots without locks");
std::array<TempSlot, kSlots> g_temp_slots;

// A slot for `temp`, or -1 when all are taken or the path is too long (the file is then
// not removed on a signal; it still is on every other path).
int register_temp(const std::string& temp) {
    if (temp.size() >= kPathBytes) return -1;
    for (std::size_t i = 0; i < kSlots; ++i) {
        int expected = kFree;
        if (g_temp_slots[i].state.compare_exchange_strong(expected, kFilling)) {
            std::memcpy(g_temp_slots[i].path.data(), temp.c_str(), temp.size() + 1);
            g_temp_slots[i].state.store(kReady);
            return static_cast<int>(i);
        }
    }
    return -1;
}

void unregister_temp(int slot) {
    if (slot >= 0) g_temp_slots[static_cast<std::size_t>(slot)].state.store(kFree);
}

extern "C" void remove_temporaries_and_reraise(int signal) {
    for (TempSlot& slot : g_temp_slots) {
        if (slot.state.load() == kReady) ::unlink(slot.path.data());
    }
    // The default action then ends the process as the signal would have, so that the
    // parent (a shell, mpirun, a scheduler) sees which signal it was.
    std::signal(signal, SIG_DFL);
    std::raise(signal);
}

}  // namespace

void remove_temporary_files_on_signals() {
    for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
        // A signal ignored by whoever started us (nohup's SIGHUP, a background job's
        // SIGINT) stays ignored.
        if (std::signal(signal, remove_temporaries_and_reraise) == SIG_IGN) std::signal(signal, SIG_IGN);
    }
}

Result<AtomicFile> AtomicFile::open(const std::string& path) {
    // A device or a pipe (/dev/null, /dev/stdout, a FIFO) is written as it is: a file
    // renamed over it would replace the device node (as root, /dev/full with a regular
    // file), and being whole at once means nothing for a stream. Anything else that is
    // not a regular file (a directory, a block device) is refused, never replaced.
    struct stat existing {};
    if (::stat(path.c_str(), &existing) == 0 && !S_ISREG(existing.st_mode)) {
        if (!S_ISCHR(existing.st_mode) && !S_ISFIFO(existing.st_mode)) {
            return make_error(Error::Kind::Io, path + ": cannot write (" +
                                                   (S_ISDIR(existing.st_mode) ? "a directory" : "not a regular file") +
                                                   " is in the way)");
        }
        std::FILE* file = std::fopen(path.c_str(), "wb");
        if (file == nullptr) return make_error(Error::Kind::Io, path + ": cannot write (" + std::strerror(errno) + ")");
        AtomicFile opened(path, std::string(), file);
        opened.direct_ = true;
        return opened;
    }
    std::string temp = path + ".tmp-" + std::to_string(::getpid());
    // Unnamed while it is written (Linux's O_TMPFILE, in the output's directory so that
    // commit() can give it a name there): whatever ends the process, SIGKILL and OOM
    // included, nothing is left. Where the file system cannot, a named temporary file,
    // which remove_temporary_files_on_signals() covers.
    const std::string dir = std::filesystem::path(path).parent_path().string();
    const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
    if (fd >= 0) {
        std::FILE* file = ::fdopen(fd, "wb");
        if (file != nullptr) {
            AtomicFile opened(path, std::move(temp), file);
            opened.unnamed_ = true;
            return opened;
        }
        ::close(fd);
    }
    std::FILE* file = std::fopen(temp.c_str(), "wb");
    if (file == nullptr) {
        return make_error(Error::Kind::Io, path + ": cannot write (" + std::strerror(errno) + ")");
    }
    AtomicFile opened(path, std::move(temp), file);
    opened.slot_ = register_temp(opened.temp_);
    return opened;
}

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : path_(std::move(other.path_)), temp_(std::move(other.temp_)), file_(other.file_), failed_(other.failed_),
      error_(other.error_), slot_(other.slot_), unnamed_(other.unnamed_), direct_(other.direct_) {
    other.file_ = nullptr;
    other.slot_ = -1;
}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
    if (this != &other) {
        discard();
        path_ = std::move(other.path_);
        temp_ = std::move(other.temp_);
        file_ = other.file_;
        failed_ = other.failed_;
        error_ = other.error_;
        slot_ = other.slot_;
        unnamed_ = other.unnamed_;
        direct_ = other.direct_;
        other.file_ = nullptr;
        other.slot_ = -1;
    }
    return *this;
}

AtomicFile::~AtomicFile() { discard(); }

void AtomicFile::discard() {
    if (file_ != nullptr) {
        std::fclose(file_);
        if (!unnamed_ && !direct_) std::remove(temp_.c_str());
        file_ = nullptr;
    }
    unregister_temp(slot_);
    slot_ = -1;
}

void AtomicFile::write(const void* data, std::size_t size) {
    if (file_ == nullptr || failed_ || size == 0) return;
    if (std::fwrite(data, 1, size, file_) != size) {
        failed_ = true;
        error_ = errno;  // why, for commit()'s message (later calls may change errno)
    }
}

std::uint64_t AtomicFile::position() const {
    if (file_ == nullptr) return 0;
    const off_t at = ::ftello(file_);
    return at < 0 ? 0 : static_cast<std::uint64_t>(at);
}

void AtomicFile::skip(std::uint64_t size) {
    if (file_ == nullptr || failed_ || size == 0) return;
    // A hole until the other process writes it; the file ends where the last write does.
    if (size > static_cast<std::uint64_t>(INT64_MAX) || ::fseeko(file_, static_cast<off_t>(size), SEEK_CUR) != 0) {
        failed_ = true;
        error_ = errno;
    }
}

Result<std::string> AtomicFile::share() {
    assert(file_ != nullptr && "share() after commit() or a move");
    if (direct_) return make_error(Error::Kind::Io, path_ + ": a device or a pipe cannot be written by several processes");
    if (failed_ || std::fflush(file_) != 0) {
        return make_error(Error::Kind::Io, path_ + ": write failed (" + std::strerror(failed_ ? error_ : errno) + ")");
    }
    if (unnamed_) {
        // The unnamed file gets its temporary name now, as commit() would give it; from
        // here on it is a named temporary file (removed on failure and on signals).
        slot_ = register_temp(temp_);
        std::remove(temp_.c_str());  // a stale one of a dead process with our pid
        const std::string self = "/proc/self/fd/" + std::to_string(::fileno(file_));
        if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, temp_.c_str(), AT_SYMLINK_FOLLOW) != 0) {
            const int saved = errno;
            unregister_temp(slot_);
            slot_ = -1;
            return make_error(Error::Kind::Io, path_ + ": cannot name the temporary file " + temp_ + " (" +
                                                   std::strerror(saved) + ")");
        }
        unnamed_ = false;
    }
    return temp_;
}

Result<void> AtomicFile::commit() {
    assert(file_ != nullptr && "commit() twice or after a move");
    if (direct_) {
        // A device or a pipe: nothing to sync or rename.
        bool ok = !failed_ && std::fflush(file_) == 0;
        const int saved = failed_ ? error_ : errno;
        ok = (std::fclose(file_) == 0) && ok;
        file_ = nullptr;
        if (!ok) return make_error(Error::Kind::Io, path_ + ": write failed (" + std::strerror(saved) + ")");
        return {};
    }
    bool ok = !failed_ && std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
    int saved = failed_ ? error_ : errno;
    if (ok && unnamed_) {
        // The unnamed file gets the temporary name, then the rename below puts it in
        // place atomically (linkat() cannot replace an existing file). Registered first,
        // so that a signal between the two removes it.
        slot_ = register_temp(temp_);
        std::remove(temp_.c_str());  // a stale one of a dead process with our pid
        const std::string self = "/proc/self/fd/" + std::to_string(::fileno(file_));
        ok = ::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, temp_.c_str(), AT_SYMLINK_FOLLOW) == 0;
        saved = errno;
    }
    const bool linked = ok && unnamed_;  // the unnamed file has its temporary name now
    if (std::fclose(file_) != 0 && ok) {
        ok = false;
        saved = errno;
    }
    file_ = nullptr;
    if (!ok) {
        if (!unnamed_ || linked) std::remove(temp_.c_str());
        unregister_temp(slot_);
        slot_ = -1;
        return make_error(Error::Kind::Io, path_ + ": write failed (" + std::strerror(saved) + ")");
    }
    const bool renamed = std::rename(temp_.c_str(), path_.c_str()) == 0;
    saved = errno;
    if (!renamed) std::remove(temp_.c_str());
    // After the rename: a signal in between unlinks a name that is gone, which is harmless.
    unregister_temp(slot_);
    slot_ = -1;
    if (!renamed) return make_error(Error::Kind::Io, path_ + ": cannot rename into place (" + std::strerror(saved) + ")");
    return {};
}

bool same_file(const std::string& a, const std::string& b) {
    std::error_code ec;
    if (std::filesystem::equivalent(a, b, ec)) return true;
    std::error_code ea, eb;
    const std::filesystem::path ca = std::filesystem::weakly_canonical(a, ea), cb = std::filesystem::weakly_canonical(b, eb);
    return !ea && !eb && ca == cb;
}

}  // namespace kodawari
