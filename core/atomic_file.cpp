#include "core/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <csignal>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"

namespace probeloop {
namespace {

// The temporary files the signal handler removes: the one being written, and with a batch open
// every pending one. Fixed buffers (no allocation in the handler); a slot counts only once its
// path is complete.
constexpr std::size_t kSlots = 1024, kPathMax = 4096, kArena = 1 << 20;
char g_arena[kArena];
std::size_t g_start[kSlots];
volatile std::sig_atomic_t g_slots = 0;
std::size_t g_used = 0;

extern "C" void onInterrupt(int signal) {
  const int n = g_slots;
  for (int i = 0; i < n; ++i) ::unlink(g_arena + g_start[i]);  // async-signal-safe
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

// Adds `tmp` to the paths removed on an interrupt; false when the table is full (the file is
// still atomic, only not cleaned up on SIGINT).
bool registerTemporary(const std::string& tmp) {
  if (g_slots >= static_cast<int>(kSlots) || tmp.size() >= kPathMax || g_used + tmp.size() + 1 > kArena) return false;
  std::memcpy(g_arena + g_used, tmp.c_str(), tmp.size() + 1);
  g_start[g_slots] = g_used;
  g_used += tmp.size() + 1;
  std::atomic_signal_fence(std::memory_order_seq_cst);  // the path before the count
  g_slots = g_slots + 1;
  return true;
}
void forgetTemporaries(int keep) {
  g_slots = keep;
  std::atomic_signal_fence(std::memory_order_seq_cst);
  g_used = keep == 0 ? 0 : g_used;
}

struct Pending {
  std::string path, tmp;
};
bool g_batch_open = false;
std::vector<Pending> g_pending;

std::string key(const std::string& path) {
  std::error_code ec;
  const auto abs = std::filesystem::absolute(path, ec);
  return (ec ? std::filesystem::path(path) : abs).lexically_normal().string();
}

// Writes `content` to `tmp` (flushed), or throws naming `path`.
void writeTemporary(const std::string& path, const std::string& tmp, const std::string& content) {
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError(path, 0, std::string("cannot write: ") + std::strerror(errno));
  out.write(content.data(), static_cast<std::streamsize>(content.size()));
  out.flush();
  if (!out) {
    out.close();
    std::remove(tmp.c_str());
    throw InputError(path, 0, "write failed (disk full?)");
  }
}

void renameIntoPlace(const std::string& path, const std::string& tmp) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw InputError(path, 0, "cannot rename temporary file into place: " + ec.message());
  }
}

}  // namespace

void removeTemporaryFileOnInterrupt() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    // A signal the parent ignores (a background job's SIGINT) stays ignored.
    struct sigaction previous {};
    if (::sigaction(sig, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) continue;
    ::sigaction(sig, &action, nullptr);
  }
  // `probeloop plan ... | head -1`: a reader that stops reading must not kill the command
  // between its summary and the commit of its outputs; the write to stdout fails quietly.
  ::signal(SIGPIPE, SIG_IGN);
}

namespace {

// What the rename would fail on is refused before anything is staged or renamed: a commit
// then cannot stop half-way over a folder in an output's place.
void prepareTarget(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;
  const auto status = fs::symlink_status(target, ec);
  if (!ec && fs::is_directory(status)) throw InputError(path, 0, "cannot write: a folder of that name is in the way");
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec) throw InputError(path, 0, "cannot create its folder: " + ec.message());
  }
}

void replaceNow(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  const int before = g_slots;
  registerTemporary(tmp);
  try {
    writeTemporary(path, tmp, content);
    renameIntoPlace(path, tmp);
  } catch (...) {
    forgetTemporaries(before);
    throw;
  }
  forgetTemporaries(before);
}

}  // namespace

void writeFileAtomic(const std::string& path, const std::string& content) {
  prepareTarget(path);
  if (g_batch_open) {
    // The same output written twice in one command: the later content wins, one temporary.
    const std::string k = key(path);
    for (const auto& p : g_pending)
      if (key(p.path) == k) {
        writeTemporary(path, p.tmp, content);
        return;
      }
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(g_pending.size());
    registerTemporary(tmp);
    g_pending.push_back({path, tmp});
    writeTemporary(path, tmp, content);
    return;
  }
  replaceNow(path, content);
}

void writeLiveFileAtomic(const std::string& path, const std::string& content) {
  prepareTarget(path);
  replaceNow(path, content);
}

OutputBatch::OutputBatch() {
  if (g_batch_open) throw std::logic_error("OutputBatch: a batch is already open");
  g_batch_open = true;
  g_pending.clear();
}

OutputBatch::~OutputBatch() {
  for (const auto& p : g_pending) std::remove(p.tmp.c_str());
  forgetTemporaries(0);
  g_pending.clear();
  g_batch_open = false;
}

void OutputBatch::commit() {
  std::vector<Pending> pending;
  pending.swap(g_pending);
  for (std::size_t i = 0; i < pending.size(); ++i) {
    try {
      renameIntoPlace(pending[i].path, pending[i].tmp);
    } catch (...) {
      for (std::size_t k = i + 1; k < pending.size(); ++k) std::remove(pending[k].tmp.c_str());
      forgetTemporaries(0);
      throw;
    }
  }
  forgetTemporaries(0);
}

std::string pendingOutput(const std::string& path) {
  if (!g_batch_open || g_pending.empty()) return "";
  const std::string k = key(path);
  for (const auto& p : g_pending)
    if (key(p.path) == k) return p.tmp;
  return "";
}

}  // namespace probeloop
