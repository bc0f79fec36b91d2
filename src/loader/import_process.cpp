// Why a child process, and why posix_spawn of an executable of our own rather than a fork that
// imports in the child: the loader runs inside the node, and inside a nodelet manager, whose other
// threads (roscpp's, the manager's) may hold locks at the moment of a fork (the allocator's,
// iostreams', assimp's own); a forked child that then ran assimp, which allocates throughout, could
// deadlock on them. Between fork and exec only async-signal-safe calls are allowed, and
// posix_spawn does just that (glibc: clone(CLONE_VM | CLONE_VFORK), then exec). A process of its
// own also gets limits of its own: the importer sets RLIMIT_AS (the memory bound) on itself before
// it reads a file, and the loader enforces the time bound with a deadline and SIGKILL. Checking a
// format's counts against the file size before assimp reads it would not do: the corrupt files
// found so far make assimp's Collada parser loop while allocating, or crash, with plausible counts.
//
// One process serves a loader's files in turn: starting one (exec, loading assimp) costs more
// than importing a small mesh, and the TurtleBot3 world and robot have eight imports.
#include "import_process.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <thread>
#include <vector>

#include "import_protocol.h"

extern char** environ;

namespace laser_raycast {
namespace import_process {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string text(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// A file descriptor closed on scope exit.
class Fd {
 public:
  explicit Fd(int fd = -1) : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { reset(); }
  int get() const { return fd_; }
  void reset(int fd = -1) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_;
};

MeshImportBoundError memoryBoundError(const MeshImportBounds& bounds) {
  return MeshImportBoundError(
      "importing it needs more than the memory bound of " + text(bounds.max_memory_mb) +
          " MB for one mesh file; stopped (a corrupt or hostile file can make assimp allocate "
          "without limit; a sound mesh this large needs a larger bound: the node's "
          "~mesh_import_max_memory_mb, cast_scan's --mesh-import-max-memory-mb)",
      MeshImportBoundError::Bound::kMemory, bounds.max_memory_mb);
}

MeshImportBoundError timeBoundError(const MeshImportBounds& bounds) {
  return MeshImportBoundError(
      "importing it took longer than the time bound of " + text(bounds.max_seconds) +
          " s for one mesh file; stopped (a corrupt or hostile file can make assimp loop; a "
          "sound mesh this large needs a longer bound: the node's ~mesh_import_timeout, "
          "cast_scan's --mesh-import-timeout)",
      MeshImportBoundError::Bound::kTime, bounds.max_seconds);
}

// Starts the importer with both its standard input and output on one end of a new socket pair
// (the other end in *socket), every signal at its default disposition and none blocked, and the
// parent's environment without LD_PRELOAD: a preloaded sanitizer runtime (a nodelet manager under
// ASan) reserves terabytes of address space, which the memory bound would count.
pid_t spawnImporter(const MeshImportBounds& bounds, Fd* socket) {
  const std::string importer = importerPath();
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
    throw SceneLoadError(std::string("cannot create a socket for the mesh importer: ") +
                         std::strerror(errno));
  }
  Fd ours(fds[0]), theirs(fds[1]);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, theirs.get(), STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, theirs.get(), STDOUT_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none, all;
  sigemptyset(&none);
  sigfillset(&all);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setsigdefault(&attributes, &all);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);

  std::ostringstream memory, seconds;
  memory.precision(17);
  seconds.precision(17);
  memory << bounds.max_memory_mb;
  seconds << bounds.max_seconds;
  const std::string memory_arg = memory.str(), seconds_arg = seconds.str();
  char* const argv[] = {
      const_cast<char*>(importer.c_str()),    const_cast<char*>("--max-memory-mb"),
      const_cast<char*>(memory_arg.c_str()),  const_cast<char*>("--max-seconds"),
      const_cast<char*>(seconds_arg.c_str()), nullptr};
  std::vector<char*> env;
  for (char** e = environ; e && *e; ++e) {
    if (std::strncmp(*e, "LD_PRELOAD=", 11) != 0) env.push_back(*e);
  }
  env.push_back(nullptr);

  pid_t pid = -1;
  const int rc = posix_spawn(&pid, importer.c_str(), &actions, &attributes, argv, env.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (rc != 0) {
    throw SceneLoadError("cannot start the mesh importer " + importer + ": " + std::strerror(rc));
  }
  socket->reset(ours.release());
  return pid;
}

// How reading a reply ended.
enum class ReadEnd { kComplete, kEndOfFile, kDeadline, kTooLong };

// Reads one reply from fd into *bytes: until it is complete (its size is announced at its start),
// the input ends, the deadline passes, or it announces more than max_bytes. Throws SceneLoadError
// for a reply that is not one.
ReadEnd readReply(int fd, Clock::time_point deadline, std::uint64_t max_bytes, std::string* bytes) {
  std::optional<std::uint64_t> size;
  std::vector<char> buffer(1 << 16);
  while (!size || bytes->size() < *size) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return ReadEnd::kDeadline;
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count() + 1, 1000)));
    if (ready < 0 && errno != EINTR) {
      throw SceneLoadError(std::string("waiting for the mesh importer failed: ") +
                           std::strerror(errno));
    }
    if (ready <= 0) continue;
    const std::size_t want =
        size ? std::min<std::uint64_t>(buffer.size(), *size - bytes->size()) : buffer.size();
    const ssize_t n = ::read(fd, buffer.data(), want);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) return ReadEnd::kEndOfFile;  // an error here also means the importer is gone
    bytes->append(buffer.data(), static_cast<std::size_t>(n));
    if (!size) {
      size = import_protocol::replySize(*bytes);
      if (size && *size > max_bytes) return ReadEnd::kTooLong;
      if (size) bytes->reserve(*size);
    }
  }
  return ReadEnd::kComplete;
}

// Why the importer ended without a complete reply, from its wait status (-1: unknown).
[[noreturn]] void throwEnded(int status, const MeshImportBounds& bounds) {
  if (status != -1 && WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    // RLIMIT_CPU, the importer's own backstop for the time bound.
    if (signal == SIGXCPU) throw timeBoundError(bounds);
    throw SceneLoadError("the mesh importer (assimp) crashed on it (signal " +
                         std::to_string(signal) + ", " + strsignal(signal) +
                         "): the file is corrupt");
  }
  throw SceneLoadError(
      "the mesh importer ended without a reply (exit status " +
      (status == -1 ? std::string("unknown") : std::to_string(WEXITSTATUS(status))) + ")");
}

}  // namespace

// The running importer: killed and reaped when destroyed.
class MeshImporter::Process {
 public:
  explicit Process(const MeshImportBounds& bounds) : bounds_(bounds) {
    pid_ = spawnImporter(bounds, &socket_);
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;
  ~Process() {
    if (pid_ > 0) end(Clock::now());
  }

  const MeshImportBounds& bounds() const { return bounds_; }
  int served() const { return served_; }
  void countServed() { ++served_; }

  // Sends a request and reads its reply into *bytes, until deadline.
  ReadEnd request(const std::string& path, const Eigen::Vector3d& scale, Clock::time_point deadline,
                  std::string* bytes) {
    // A failed send means the process is gone: reading then finds the end of its output.
    import_protocol::writeRequest(socket_.get(), path, scale);
    // The importer cannot hold more than its address space.
    const auto max_bytes = static_cast<std::uint64_t>(bounds_.max_memory_mb * 1024 * 1024);
    return readReply(socket_.get(), deadline, max_bytes, bytes);
  }

  // Waits for the process to exit until deadline, then kills it; returns its wait status, or -1
  // if it cannot be known (SIGCHLD ignored: the kernel reaps children itself).
  int end(Clock::time_point deadline) {
    socket_.reset();  // an idle importer exits at the end of its input
    auto pause = std::chrono::microseconds(20);
    int status = -1;
    for (;;) {
      const pid_t r = ::waitpid(pid_, &status, WNOHANG);
      if (r == pid_ || (r < 0 && errno != EINTR)) break;
      if (Clock::now() >= deadline) {
        ::kill(pid_, SIGKILL);
        while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
        }
        break;
      }
      std::this_thread::sleep_for(pause);
      pause = std::min(pause * 2, std::chrono::microseconds(10000));
    }
    pid_ = -1;
    return status;
  }

 private:
  MeshImportBounds bounds_;
  pid_t pid_ = -1;
  Fd socket_;
  int served_ = 0;  // files it has replied to
};

MeshImporter::MeshImporter() = default;
MeshImporter::~MeshImporter() = default;

mesh_file::MeshData MeshImporter::import(const std::string& path, const Eigen::Vector3d& scale,
                                         const MeshImportBounds& bounds) {
  const Clock::time_point deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(bounds.max_seconds));
  // A process that fails after serving other files is retried once in a fresh one: their
  // allocations may have fragmented its address space. The deadline stays.
  for (int attempt = 0;; ++attempt) {
    if (process_ && (process_->bounds().max_memory_mb != bounds.max_memory_mb ||
                     process_->bounds().max_seconds != bounds.max_seconds)) {
      process_.reset();
    }
    if (!process_) process_ = std::make_unique<Process>(bounds);
    const bool retry = process_->served() > 0 && attempt == 0;
    std::string bytes;
    ReadEnd end;
    import_protocol::Reply reply;
    try {
      end = process_->request(path, scale, deadline, &bytes);
      if (end == ReadEnd::kComplete) reply = import_protocol::parseReply(bytes);
    } catch (const SceneLoadError&) {
      process_.reset();  // out of step with us: not to be trusted with another file
      throw;
    }
    if (end == ReadEnd::kComplete && reply.status != import_protocol::Status::kOutOfMemory) {
      process_->countServed();
      if (reply.status == import_protocol::Status::kMesh) return std::move(reply.mesh);
      throw SceneLoadError(reply.message);
    }
    // Exceeded a bound, or died: this process is done (after an out-of-memory reply it exits).
    const int status =
        process_->end(end == ReadEnd::kComplete || end == ReadEnd::kEndOfFile
                          ? std::min(deadline, Clock::now() + std::chrono::seconds(1))
                          : Clock::now());
    process_.reset();
    if (end == ReadEnd::kDeadline) throw timeBoundError(bounds);
    if (retry) continue;
    if (end == ReadEnd::kEndOfFile) throwEnded(status, bounds);
    throw memoryBoundError(bounds);  // an out-of-memory reply, or one too long to be real
  }
}

std::string importerPath() {
  const char* env = std::getenv(kImporterEnv);
  if (env && *env) {
    if (::access(env, X_OK) != 0) {
      throw SceneLoadError(std::string("the mesh importer in $") + kImporterEnv + ", " + env +
                           ", is not an executable file");
    }
    return env;
  }
  std::vector<std::string> tried;
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(&importerPath), &info) && info.dli_fname) {
    std::error_code ec;
    fs::path self = fs::weakly_canonical(info.dli_fname, ec);
    if (ec) self = info.dli_fname;
    const fs::path dir = self.parent_path();
    for (const fs::path& candidate : {dir / "laser_raycast" / kImporterName, dir / kImporterName}) {
      if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
      tried.push_back(candidate.string());
    }
  }
  std::string where;
  for (const std::string& t : tried) where += (where.empty() ? "" : ", ") + t;
  throw SceneLoadError(std::string("cannot find the mesh importer ") + kImporterName +
                       " (looked for " + (where.empty() ? "nothing: no library path" : where) +
                       "; set $" + kImporterEnv + " to its path)");
}

}  // namespace import_process
}  // namespace laser_raycast
