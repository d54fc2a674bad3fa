// `kodawari completion bash`: a bash completion script written from the CLI11 definitions
// of every command, so that it cannot fall behind them.
#include <cstdio>
#include <string>
#include <vector>

#include "commands.hpp"

namespace kodawari::cli {
namespace {

// An option's value is a file when its value name says so (FILE.glb, SCENE.json, DIR, ...).
enum class ValueKind { None, File, Directory, Choice, Word };

ValueKind value_kind(const CLI::Option& option) {
    if (option.get_type_size() == 0) return ValueKind::None;
    const std::string type = option.get_type_name();
    if (type == "DIR") return ValueKind::Directory;
    if (type.find('.') != std::string::npos || type == "SCENE" || type == "CHARACTER" || type == "PART") return ValueKind::File;
    // A value name in lower case lists the words themselves (auto|vulkan|cpu, bash).
    if (!type.empty() && type.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_|") == std::string::npos) {
        return ValueKind::Choice;
    }
    return ValueKind::Word;
}

std::string choices(const CLI::Option& option) {
    std::string words = option.get_type_name();
    for (char& c : words) {
        if (c == '|') c = ' ';
    }
    return words;
}

// Adds the case branches of one App (`path`: its words after "kodawari", space-separated).
void describe(const CLI::App& app, const std::string& path, std::string& children, std::string& words, std::string& values) {
    std::string subcommands;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
        subcommands += (subcommands.empty() ? "" : " ") + sub->get_name();
        children += "            \"" + path + "/" + sub->get_name() + "\") path=\"" + (path.empty() ? "" : path + " ") +
                    sub->get_name() + "\" ;;\n";
    }
    std::string options;
    bool positional_files = false;
    for (const CLI::Option* option : app.get_options()) {
        if (option->get_positional()) {
            positional_files = positional_files || value_kind(*option) == ValueKind::File;
            if (value_kind(*option) == ValueKind::Choice) subcommands += (subcommands.empty() ? "" : " ") + choices(*option);
            continue;
        }
        for (const std::string& name : option->get_lnames()) {
            options += (options.empty() ? "" : " ") + ("--" + name);
            std::string action;
            switch (value_kind(*option)) {
                case ValueKind::None: break;
                case ValueKind::File: action = "COMPREPLY=($(compgen -f -- \"$cur\"))"; break;
                case ValueKind::Directory: action = "COMPREPLY=($(compgen -d -- \"$cur\"))"; break;
                case ValueKind::Choice: action = "COMPREPLY=($(compgen -W \"" + choices(*option) + "\" -- \"$cur\"))"; break;
                case ValueKind::Word: action = "COMPREPLY=()"; break;
            }
            if (!action.empty()) values += "        \"" + path + " --" + name + "\") " + action + "; return ;;\n";
        }
    }
    if (app.get_help_ptr() != nullptr) options += " --help";
    words += "        \"" + path + "\") options=\"" + options + "\"; commands=\"" + subcommands + "\"; files=" +
             (positional_files ? "1" : "0") + " ;;\n";
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
        describe(*sub, (path.empty() ? "" : path + " ") + sub->get_name(), children, words, values);
    }
}

}  // namespace

std::string bash_completion(const CLI::App& app) {
    std::string children, words, values;
    describe(app, "", children, words, values);
    return "# bash completion of kodawari, written by `kodawari completion bash` from its own option definitions.\n"
           "_kodawari() {\n"
           "    local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]}\n"
           "    local path=\"\" i options=\"\" commands=\"\" files=0\n"
           "    # The subcommands named so far, e.g. \"bench chains\".\n"
           "    for ((i = 1; i < COMP_CWORD; i++)); do\n"
           "        case \"$path/${COMP_WORDS[i]}\" in\n" +
           children +
           "        esac\n"
           "    done\n"
           "    # The value of the option before the cursor.\n"
           "    case \"$path $prev\" in\n" +
           values +
           "    esac\n"
           "    case \"$path\" in\n" +
           words +
           "    esac\n"
           "    if [[ $cur == -* ]]; then\n"
           "        COMPREPLY=($(compgen -W \"$options\" -- \"$cur\"))\n"
           "    else\n"
           "        COMPREPLY=($(compgen -W \"$commands\" -- \"$cur\"))\n"
           "        if ((files)); then COMPREPLY+=($(compgen -f -- \"$cur\")); fi\n"
           "    fi\n"
           "}\n"
           "complete -F _kodawari kodawari\n";
}

namespace {

struct CompletionOptions {
    std::string shell;
};

}  // namespace

Command add_completion(CLI::App& app) {
    auto o = std::make_shared<CompletionOptions>();
    CLI::App* c = app.add_subcommand("completion", "print a shell completion script: kodawari completion bash > "
                                                   "~/.local/share/bash-completion/completions/kodawari");
    const CLI::Validator shells(
        [](std::string& shell) -> std::string { return shell == "bash" ? "" : "expected bash, got \"" + shell + "\""; }, "");
    c->add_option("shell", o->shell, "the shell")->required()->check(shells)->type_name("bash");
    const CLI::App* root = &app;
    // The option writes into *o when the command line is parsed, after this returns: the
    // command holds it.
    return {c, [root, o] {
                const std::string script = bash_completion(*root);
                const bool written = std::fwrite(script.data(), 1, script.size(), stdout) == script.size();
                return written && std::fflush(stdout) == 0 ? kExitOk : kExitFailure;
            }};
}

}  // namespace kodawari::cli
