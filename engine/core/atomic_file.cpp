#include "kodawari/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <unistd.h>

namespace kodawari {

Result<AtomicFile> AtomicFile::open(const std::string& path) {
    std::string temp = path + ".tmp-" + std::to_string(::getpid());
    std::FILE* file = std::fopen(temp.c_str(), "wb");
    if (file == nullptr) {
        return make_error(Error::Kind::Io, path + ": cannot write (" + std::strerror(errno) + ")");
    }
    return AtomicFile(path, std::move(temp), file);
}

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : path_(std::move(other.path_)), temp_(std::move(other.temp_)), file_(other.file_), failed_(other.failed_) {
    other.file_ = nullptr;
}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
    if (this != &other) {
        discard();
        path_ = std::move(other.path_);
        temp_ = std::move(other.temp_);
        file_ = other.file_;
        failed_ = other.failed_;
        other.file_ = nullptr;
    }
    return *this;
}

AtomicFile::~AtomicFile() { discard(); }

void AtomicFile::discard() {
    if (file_ != nullptr) {
        std::fclose(file_);
        std::remove(temp_.c_str());
        file_ = nullptr;
    }
}

void AtomicFile::write(const void* data, std::size_t size) {
    if (file_ == nullptr || failed_ || size == 0) return;
    if (std::fwrite(data, 1, size, file_) != size) failed_ = true;
}

Result<void> AtomicFile::commit() {
    assert(file_ != nullptr && "commit() twice or after a move");
    bool ok = !failed_ && std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
    int saved = errno;
    ok = (std::fclose(file_) == 0) && ok;
    file_ = nullptr;
    if (!ok) {
        std::remove(temp_.c_str());
        return make_error(Error::Kind::Io, path_ + ": write failed (" + std::strerror(saved) + ")");
    }
    if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
        saved = errno;
        std::remove(temp_.c_str());
        return make_error(Error::Kind::Io, path_ + ": cannot rename into place (" + std::strerror(saved) + ")");
    }
    return {};
}

}  // namespace kodawari
