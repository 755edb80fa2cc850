// Writes a whole file or nothing: content goes to "<path>.tmp-<pid>" in the same folder,
// is flushed, then renamed over <path>. A failure leaves any previous file untouched, and so
// does a crash or a kill at any moment: rename(2) replaces the file in one step, so a reader
// sees the old file or the new one, never a torn one. (No fsync: a power cut right after the
// rename may still lose the new content; that is outside what this promises.)
//
// A command's outputs together (docs/reliability.md#all-or-nothing): while an OutputBatch is
// open, writeFileAtomic only writes the temporary files; commit() renames them all into
// place, in the order they were written, after the command has succeeded. A batch closed
// without commit() (an exception, an early return) removes its temporaries: every output
// keeps its old version. Within the batch, readFile() of a path written earlier reads the
// pending content (a command may read back what it wrote).
#pragma once
#include <string>

#include "core/input_file.hpp"

namespace probeloop {

void writeFileAtomic(const std::string& path, const std::string& content);

// The same, replaced at once even while a batch is open: a live output that another program
// reads while the command runs (campaign run --follow's controller file and dashboard, rewritten
// after every pass). It is not part of the batch: an error later does not take it back.
void writeLiveFileAtomic(const std::string& path, const std::string& content);

// SIGINT / SIGTERM / SIGHUP while a file is being written remove its temporary file (with a
// batch open, every pending one) before the process ends with the signal's usual status (128 +
// signal); SIGPIPE is ignored (a closed stdout must not stop a command before its commit).
// Called once by main(). A SIGKILL cannot be caught: it may leave "<path>.tmp-<pid>" files
// beside the old ones (never in their place).
void removeTemporaryFileOnInterrupt();

class OutputBatch {
 public:
  OutputBatch();   // one at a time; a second open batch is a logic_error
  ~OutputBatch();  // without commit(): the temporaries are removed
  // Renames every pending file into place. A rename that fails (the disk, permissions) stops
  // there with an InputError naming the file; the files renamed before it are in place (each
  // one whole), the rest keep their old versions and their temporaries are removed.
  void commit();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
};

// The temporary file holding `path`'s pending content in the open batch; empty if none.
std::string pendingOutput(const std::string& path);

}  // namespace probeloop
