// Writes a whole file or nothing: content goes to "<path>.tmp-<pid>" in the same folder,
// is flushed, then renamed over <path>. A failure leaves any previous file untouched.
#pragma once
#include <string>

namespace probeloop {

void writeFileAtomic(const std::string& path, const std::string& content);
std::string readFile(const std::string& path);  // InputError if unreadable

}  // namespace probeloop
