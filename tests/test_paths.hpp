// Where the tests find the source tree, the command and the Node tools of this build.
//
// They are functions defined in one generated file (test_paths.cpp in the build folder,
// tests/CMakeLists.txt) rather than macros on every test file's command line: an absolute
// path on the command line made ccache miss every test file whenever the tree was built
// from another folder (CI's clean clone against a developer's tree: 50 of 213 files of the
// asan build, 11 minutes on a 2-core machine). The macros keep the tests' spelling.
#pragma once

namespace kodawari::test_paths {
/// The source tree's root (PROJECT_SOURCE_DIR).
const char* source_dir();
/// The `kodawari` command built beside the tests.
const char* cli();
/// The folder of the Node tools scripts/setup installs (.tools/npm).
const char* node_tools();
}  // namespace kodawari::test_paths

#define KODAWARI_SOURCE_DIR (::kodawari::test_paths::source_dir())
#define KODAWARI_CLI (::kodawari::test_paths::cli())
#define KODAWARI_NODE_TOOLS (::kodawari::test_paths::node_tools())
