// A compacted .glb written by the ranks together: see shared_glb.hpp.
#include "export/shared_glb.hpp"

#include <cstring>
#include <utility>
#include <vector>

#include <sys/stat.h>

namespace kodawari::gltf {

bool is_device_or_pipe(const std::string& path) {
    struct stat existing {};
    return !path.empty() && ::stat(path.c_str(), &existing) == 0 && !S_ISREG(existing.st_mode);
}

Result<void> check_share(const std::string& path, bool shareable, const char* needs, const char* items, std::size_t begin,
                         std::size_t end, std::size_t count, bool started) {
    if (!shareable) {
        return make_error(Error::Kind::InvalidInput,
                          path + ": this writer's work cannot be shared between ranks (it needs " + needs + ")");
    }
    if (begin > end || end > count || started) {
        return make_error(Error::Kind::InvalidInput, path + ": " + items + " [" + std::to_string(begin) + ", " +
                                                         std::to_string(end) + ") are not a range of the " +
                                                         std::to_string(count) + " " + items +
                                                         ", given before the first frame");
    }
    return {};
}

Result<void> finish_shared_glb(Communicator& ranks, const std::string& path, Result<CompactKeys> mine,
                               std::span<const std::byte> extra,
                               const std::function<Result<void>(std::size_t rank, std::span<const std::byte> extra)>& take_extra,
                               const std::function<Result<void>(AtomicFile& file, CompactKeys& keys)>& write) {
    KW_TRY(ranks.agree(mine ? Result<void>{} : Result<void>{mine.error()}));
    CompactKeys& keys = mine.value();
    const bool root = ranks.rank() == 0;

    // To rank 0: the length of this part's description, the description, the extra bytes.
    std::vector<std::byte> message(sizeof(std::uint64_t));
    {
        const std::vector<std::byte> description = keys.describe();
        const std::uint64_t length = description.size();
        std::memcpy(message.data(), &length, sizeof length);
        message.insert(message.end(), description.begin(), description.end());
        if (!root) message.insert(message.end(), extra.begin(), extra.end());
    }
    std::vector<std::byte> all;
    std::vector<std::size_t> sizes;
    ranks.gather(message, all, sizes);

    if (root) {
        // The plan, broadcast once whatever happens: the temporary file's name, then rank
        // r's place in it (r >= 1), 8 bytes each; empty when rank 0 failed before.
        Result<void> parts;
        bool planned = false;
        const Result<void> written = [&]() -> Result<void> {
            std::vector<std::vector<std::byte>> descriptions;
            std::size_t at = sizes.empty() ? 0 : sizes[0];
            for (std::size_t r = 1; r < sizes.size(); ++r) {
                const std::byte* part = all.data() + at;
                std::uint64_t length = 0;
                if (sizes[r] < sizeof length) return make_error(Error::Kind::Internal, path + ": rank " + std::to_string(r) + "'s keys are cut short");
                std::memcpy(&length, part, sizeof length);
                if (length > sizes[r] - sizeof length) {
                    return make_error(Error::Kind::Internal, path + ": rank " + std::to_string(r) + "'s keys are cut short");
                }
                descriptions.emplace_back(part + sizeof length, part + sizeof length + length);
                KW_TRY(take_extra(r, std::span(part + sizeof length + length, sizes[r] - sizeof length - length)));
                at += sizes[r];
            }
            auto offsets = keys.join(descriptions);
            if (!offsets) return offsets.error();
            return write_file_atomically(path, [&](AtomicFile& file) -> Result<void> {
                KW_TRY(write(file, keys));
                auto name = file.share();
                if (!name) return name.error();
                std::vector<std::byte> plan(name.value().size());
                std::memcpy(plan.data(), name.value().data(), plan.size());
                for (const std::uint64_t offset : offsets.value()) {
                    const std::uint64_t place = keys.written_at() + offset;
                    const auto* bytes = reinterpret_cast<const std::byte*>(&place);
                    plan.insert(plan.end(), bytes, bytes + sizeof place);
                }
                ranks.broadcast(plan);
                planned = true;
                parts = ranks.agree({});
                return parts;  // an error: not committed
            });
        }();
        if (!planned) {
            std::vector<std::byte> none;
            ranks.broadcast(none);
        }
        const Result<void> status = ranks.agree(parts ? written : Result<void>{});
        return parts ? status : parts;
    }
    std::vector<std::byte> plan;
    ranks.broadcast(plan);
    Result<void> parts;
    if (!plan.empty()) {
        const std::size_t places = static_cast<std::size_t>(ranks.size() - 1) * sizeof(std::uint64_t);
        Result<void> wrote;
        if (plan.size() <= places) {
            wrote = make_error(Error::Kind::Internal, path + ": rank 0's plan for the keys is cut short");
        } else {
            const std::string name(reinterpret_cast<const char*>(plan.data()), plan.size() - places);
            std::uint64_t place = 0;
            std::memcpy(&place, plan.data() + name.size() + static_cast<std::size_t>(ranks.rank() - 1) * sizeof place, sizeof place);
            wrote = keys.write_part(name, place);
        }
        parts = ranks.agree(wrote);
    }
    const Result<void> status = ranks.agree({});
    return parts ? status : parts;
}

}  // namespace kodawari::gltf
