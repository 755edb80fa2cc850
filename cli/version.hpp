// `probeloop --version`: the project version and the commit the binary was built from
// (written at every build by cmake/write_version.cmake; "unknown" outside a git checkout,
// "-dirty" when the tree had uncommitted changes).
#pragma once

namespace probeloop::cli {
const char* versionText();
}  // namespace probeloop::cli
