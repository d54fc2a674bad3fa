#pragma once
/// @file
/// The one error policy of the engine: fallible operations return a `[[nodiscard]]`
/// `Result<T>` that either holds a value or an `Error` with a readable reason.
/// Programmer errors (broken invariants) are asserts, not Results.

#include <cassert>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace kodawari {

/// What went wrong, for a person: names the file, the field and what was expected
/// where those apply.
struct Error {
    /// Kinds let the command line choose an exit code (bad input = 2).
    enum class Kind { InvalidInput, Io, Vulkan, Unsupported, Internal };
    Kind kind = Kind::Internal;
    std::string message;
    /// The VkResult a Vulkan call returned (0, VK_SUCCESS, when the error did not come from
    /// one), as an int so that this header names no Vulkan type: a caller can tell
    /// VK_ERROR_OUT_OF_DEVICE_MEMORY (-2) from VK_ERROR_DEVICE_LOST (-4) without parsing
    /// the message, as vk-bootstrap's errors allow.
    int vk_result = 0;
    /// When no device could be chosen: why each one was passed over
    /// ("llvmpipe (LLVM 15.0.6, 256 bits): no queue family with compute"). vk_result is then
    /// 0: no Vulkan call failed.
    std::vector<std::string> rejected_devices{};
};

/// Builds an Error of the given kind.
[[nodiscard]] inline Error make_error(Error::Kind kind, std::string message) {
    Error error;
    error.kind = kind;
    error.message = std::move(message);
    return error;
}

/// A value or an Error. Check with `ok()` (or `if (result)`) before `value()`.
template <typename T>
class [[nodiscard]] Result {
public:
    Result(T value) : data_(std::move(value)) {}              // NOLINT(google-explicit-constructor)
    Result(Error error) : data_(std::move(error)) {}          // NOLINT(google-explicit-constructor)

    [[nodiscard]] bool ok() const { return data_.index() == 0; }
    explicit operator bool() const { return ok(); }

    [[nodiscard]] T& value() & {
        assert(ok());
        return std::get<0>(data_);
    }
    [[nodiscard]] const T& value() const& {
        assert(ok());
        return std::get<0>(data_);
    }
    [[nodiscard]] T&& value() && {
        assert(ok());
        return std::get<0>(std::move(data_));
    }
    [[nodiscard]] const Error& error() const {
        assert(!ok());
        return std::get<1>(data_);
    }

private:
    std::variant<T, Error> data_;
};

/// A Result without a value.
template <>
class [[nodiscard]] Result<void> {
public:
    Result() = default;
    Result(Error error) : error_(std::move(error)), failed_(true) {}  // NOLINT(google-explicit-constructor)

    [[nodiscard]] bool ok() const { return !failed_; }
    explicit operator bool() const { return ok(); }
    [[nodiscard]] const Error& error() const {
        assert(failed_);
        return error_;
    }

private:
    Error error_;
    bool failed_ = false;
};

}  // namespace kodawari

/// Returns the error of `expr` (a Result) from the enclosing function when it failed.
#define KW_TRY(expr)                                    \
    do {                                                \
        auto kw_try_result_ = (expr);                   \
        if (!kw_try_result_.ok()) return kw_try_result_.error(); \
    } while (false)
