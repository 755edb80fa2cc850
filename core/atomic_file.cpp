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

#include "core/error.hpp"

namespace probeloop {
namespace {

// The temporary file being written, for the signal handler: a fixed buffer (no allocation
// in the handler) and a flag set only while the buffer holds a complete path.
char g_temporary[4096];
volatile std::sig_atomic_t g_writing = 0;

extern "C" void onInterrupt(int signal) {
  if (g_writing) ::unlink(g_temporary);  // async-signal-safe
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

// Marks `tmp` as the file to remove on an interrupt for the lifetime of the guard.
class TemporaryGuard {
 public:
  explicit TemporaryGuard(const std::string& tmp) {
    // One writer at a time (the CLI writes its files one after another, on one thread). A
    // path too long for the buffer is not removed on an interrupt; it is still atomic.
    if (tmp.size() < sizeof g_temporary) {
      std::memcpy(g_temporary, tmp.c_str(), tmp.size() + 1);
      std::atomic_signal_fence(std::memory_order_seq_cst);  // the path before the flag
      g_writing = 1;
    }
  }
  ~TemporaryGuard() {
    g_writing = 0;
    std::atomic_signal_fence(std::memory_order_seq_cst);
  }
  TemporaryGuard(const TemporaryGuard&) = delete;
  TemporaryGuard& operator=(const TemporaryGuard&) = delete;
};

}  // namespace

void removeTemporaryFileOnInterrupt() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  for (int sig : {SIGINT, SIGTERM}) {
    // A signal the parent ignores (a background job's SIGINT) stays ignored.
    struct sigaction previous {};
    if (::sigaction(sig, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) continue;
    ::sigaction(sig, &action, nullptr);
  }
}

void writeFileAtomic(const std::string& path, const std::string& content) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  if (target.has_parent_path()) fs::create_directories(target.parent_path());
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  const TemporaryGuard guard(tmp);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, 0, std::string("cannot write: ") + std::strerror(errno));
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw InputError(path, 0, "write failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw InputError(path, 0, "cannot rename temporary file into place: " + ec.message());
  }
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace probeloop
