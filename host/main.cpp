// kodawari: the command line of the crowd simulator. Every subcommand defines its options
// with CLI11 (host/cmd_*.cpp), so `--help`, the usage errors and the bash completion come
// from the same definitions.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <regex>
#include <string>
#include <system_error>
#include <vector>

#include "kodawari/core/atomic_file.hpp"
#include "kodawari/core/version.hpp"
#include "commands.hpp"

namespace {

constexpr const char* kEnvironment = R"(Environment: KODAWARI_DEVICE (the device when no --device), KODAWARI_ISA (the cpu
backend's SIMD instruction set when no --isa: avx512, avx2, sse4 or scalar), KODAWARI_VALIDATION=1
(as --validation), KODAWARI_FORCE_STAGING=1 (staging copies even on unified memory).
Exit status: 0 success, 1 failure (a check did not pass, a runtime error), 2 bad input or usage
(a bad option, a missing or unreadable input file, a file's content refused).
`kodawari COMMAND --help` lists a command's options; the reference is )";

// Where the reference page is: the installed copy beside the command
// (<prefix>/share/doc/kodawari/docs/command-line.md) when there is one, else its place in
// the source tree.
std::string reference_page() {
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        const std::filesystem::path installed = exe.parent_path().parent_path() / "share/doc/kodawari/docs/command-line.md";
        if (std::filesystem::exists(installed, ec)) return installed.lexically_normal().string() + ".";
    }
    return "docs/command-line.md in the source tree (installed as <prefix>/share/doc/kodawari/docs/command-line.md).";
}

// The parsed command deepest in the tree (`bench flock`), else the top.
const CLI::App* deepest_command(const CLI::App& app) {
    const CLI::App* at = &app;
    for (auto named = at->get_subcommands(); !named.empty(); named = at->get_subcommands()) at = named.front();
    return at;
}

// The words naming that command ("kodawari bench flock"; "kodawari" when none), for the
// pointer to its --help after a usage error.
std::string command_path(const CLI::App& app) {
    std::string path;
    for (const CLI::App* at = deepest_command(app); at != nullptr; at = at->get_parent()) {
        path = at->get_name() + (path.empty() ? "" : " " + path);
    }
    return path;
}

// Edits (insertions, deletions, substitutions) between two words.
std::size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t next = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0u : 1u)});
            diagonal = row[j];
            row[j] = next;
        }
    }
    return row[b.size()];
}

// What CLI11 says of arguments no option took ("The following arguments were not
// expected: 10 --frame", in reverse as the words are parsed reversed), said per argument
// in the order given, with the nearest option of the command for one that looks like a
// misspelt option (one edit for names of up to 4 letters, two beyond: `--gpu` is not
// `--mpi`). Words after `--` are positionals, never options.
void explain_extras(const CLI::App& app, const std::vector<std::string>& words) {
    const CLI::App* command = deepest_command(app);
    const std::string path = command_path(app);
    std::vector<std::string> names;
    for (const CLI::App* at : {&app, command}) {
        for (const CLI::Option* option : at->get_options()) {
            for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
        }
    }
    std::vector<std::string> unknown;
    for (const std::string& word : words) {
        if (word == "--") break;
        if (!word.starts_with("--")) continue;
        const std::string name = word.substr(0, word.find('='));
        if (name.size() > 2 && std::find(names.begin(), names.end(), name) == names.end()) unknown.push_back(name);
    }
    for (const std::string& name : unknown) {
        const std::size_t letters = name.size() - 2;
        std::string nearest;
        std::size_t best = (letters <= 4 ? 1 : 2) + 1;
        for (const std::string& candidate : names) {
            const std::size_t d = edit_distance(name, candidate);
            if (d < best) best = d, nearest = candidate;
        }
        std::fprintf(stderr, "%s: no option %s%s\n", path.c_str(), name.c_str(),
                     nearest.empty() ? "" : (" (did you mean " + nearest + "?)").c_str());
    }
    if (unknown.empty()) {
        // Every command's leftovers (the top level's too: words before the command).
        std::string list;
        for (const std::string& extra : app.remaining(true)) {
            const bool plain = !extra.empty() && extra.find_first_of(" \t") == std::string::npos;
            list += (list.empty() ? "" : " ") + (plain ? extra : "\"" + extra + "\"");
        }
        std::fprintf(stderr, "%s: arguments it does not take: %s\n", path.c_str(), list.c_str());
    }
    std::fprintf(stderr, "(`%s --help` lists the options)\n", path.c_str());
}

// CLI11's wording for an option given twice or given no value ("--json: At Most 1
// required but received 2", "--frames: 1 required N missing") in the words of the
// command's other errors: what was given and what was expected. Anything else as it is.
std::string plain_parse_error(const std::string& message) {
    std::smatch m;
    static const std::regex twice(R"(^(\S+): At Most 1 required but received (\d+)$)");
    static const std::regex missing(R"(^(\S+): 1 required (.+) missing$)");
    if (std::regex_match(message, m, twice)) return m[1].str() + ": given " + m[2].str() + " times; expected it once";
    if (std::regex_match(message, m, missing)) return m[1].str() + ": expected a value (" + m[2].str() + ") after it, got none";
    return message;
}

// The old reader refused `--name=` with nothing after "="; CLI11 would take the next
// argument as the value instead, so the check stays.
void refuse_empty_values(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--") return;
        if (arg.starts_with("--") && arg.size() > 3 && arg.back() == '=' && arg.find('=') == arg.size() - 1) {
            throw kodawari::cli::UsageError{arg.substr(0, arg.size() - 1) + ": expected a value after \"=\""};
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    using namespace kodawari::cli;
    // Ctrl-C, a scheduler's SIGTERM, a closed terminal: no temporary output stays behind.
    kodawari::remove_temporary_files_on_signals();
    CLI::App app{"kodawari: simulate crowds of birds and characters with hair and accessories (strands, rods) on Vulkan "
                 "compute or the CPU, bake them to glTF, view and render them.",
                 "kodawari"};
    app.set_version_flag("--version", "kodawari " + std::string(kodawari::version()), "print the version and exit");
    app.require_subcommand(1);
    app.footer(std::string(kEnvironment) + reference_page());
    app.get_formatter()->column_width(42);
    const std::vector<Command> commands = {add_run(app),    add_merge(app),  add_validate(app), add_bench(app),
                                           add_rig(app),    add_sketch(app), add_render(app),   add_view(app),
                                           add_info(app),   add_schema(app), add_completion(app)};
    if (argc < 2) {
        std::fputs(app.help().c_str(), stderr);
        return kExitBadInput;
    }
    // `kodawari help [COMMAND...]`, as before: the same as --help.
    std::vector<std::string> words(argv + 1, argv + argc);
    if (words[0] == "help") words.push_back("--help"), words.erase(words.begin());
    try {
        refuse_empty_values(argc, argv);
        // CLI11 would only say that a command is required.
        const auto named = app.get_subcommands([&](const CLI::App* sub) { return sub->get_name() == words[0]; });
        if (!words[0].starts_with("-") && named.empty()) {
            std::fprintf(stderr, "kodawari: unknown command \"%s\"\n(`kodawari --help` lists the commands)\n", words[0].c_str());
            return kExitBadInput;
        }
        // The same for a command's own commands (`bench birdz`, or none named): the kinds it has.
        if (!named.empty() && !named.front()->get_subcommands({}).empty()) {
            const CLI::App& command = *named.front();
            std::string kinds;
            for (const CLI::App* sub : command.get_subcommands({})) kinds += (kinds.empty() ? "" : ", ") + sub->get_name();
            const bool given = words.size() > 1 && !words[1].starts_with("-");
            const bool help = std::find_if(words.begin() + 1, words.end(), [](const std::string& w) {
                                  return w == "--help" || w == "-h" || w == "--help-all";
                              }) != words.end();
            const auto known = command.get_subcommands([&](const CLI::App* sub) { return given && sub->get_name() == words[1]; });
            if (given && known.empty()) {
                std::fprintf(stderr, "kodawari: unknown %s \"%s\": expected one of %s\n(`kodawari %s --help` lists them)\n",
                             words[0].c_str(), words[1].c_str(), kinds.c_str(), words[0].c_str());
                return kExitBadInput;
            }
            if (!given && !help) {
                std::fprintf(stderr, "kodawari: %s: name one of %s\n(`kodawari %s --help` lists them)\n", words[0].c_str(),
                             kinds.c_str(), words[0].c_str());
                return kExitBadInput;
            }
        }
        std::vector<std::string> reversed(words.rbegin(), words.rend());
        app.parse(reversed);
        for (const Command& command : commands) {
            if (command.app->parsed()) return command.run();
        }
        return kExitBadInput;  // unreachable: CLI11 requires one subcommand
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ExtrasError&) {
        explain_extras(app, words);
        return kExitBadInput;
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "kodawari: %s\n(`%s --help` lists the options)\n", plain_parse_error(e.what()).c_str(),
                     command_path(app).c_str());
        return kExitBadInput;
    } catch (const UsageError& e) {
        std::fprintf(stderr, "kodawari: %s\n(`%s --help` lists the options)\n", e.message.c_str(), command_path(app).c_str());
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kodawari: internal error: %s\n", e.what());
        return kExitFailure;
    }
}
