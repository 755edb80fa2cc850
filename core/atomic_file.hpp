// Writes a whole file or nothing: content goes to "<path>.tmp-<pid>" in the same folder,
// is flushed, then renamed over <path>. A failure leaves any previous file untouched, and so
// does a crash or a kill at any moment: rename(2) replaces the file in one step, so a reader
// sees the old file or the new one, never a torn one. (No fsync: a power cut right after the
// rename may still lose the new content; that is outside what this promises.)
#pragma once
#include <string>

namespace probeloop {

void writeFileAtomic(const std::string& path, const std::string& content);

// SIGINT / SIGTERM while a file is being written remove its temporary file before the
// process ends with the signal's usual status (128 + signal). Called once by main(). A
// SIGKILL cannot be caught: it may leave one "<path>.tmp-<pid>" beside the old file.
void removeTemporaryFileOnInterrupt();
std::string readFile(const std::string& path);  // InputError if unreadable

}  // namespace probeloop
