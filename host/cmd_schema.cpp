// `kodawari schema`: the JSON Schema of the scene format (docs/scene.schema.json), embedded
// at build time (cmake/KodawariEmbedFile.cmake), for editors and validators that are given
// the command rather than a source checkout.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string_view>

#include "commands.hpp"

namespace kodawari::embedded {
std::string_view scene_schema();
}  // namespace kodawari::embedded

namespace kodawari::cli {

namespace {

int cmd_schema() {
    const std::string_view schema = embedded::scene_schema();
    // Byte for byte: the test compares the output with the file, and a redirect to a full
    // disk must not pass for success.
    const std::size_t written = std::fwrite(schema.data(), 1, schema.size(), stdout);
    if (written != schema.size() || std::fflush(stdout) != 0) {
        const int err = errno;
        std::fprintf(stderr, "kodawari schema: cannot write the schema to standard output: %s\n", std::strerror(err));
        return kExitFailure;
    }
    return kExitOk;
}

}  // namespace

Command add_schema(CLI::App& app) {
    CLI::App* c = app.add_subcommand(
        "schema", "print the JSON Schema (draft 2020-12) of the scene format, docs/scene.schema.json, for editors and validators");
    return {c, [] { return cmd_schema(); }};
}

}  // namespace kodawari::cli
