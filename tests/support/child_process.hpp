#pragma once
// Runs a program as a child process with its stderr captured, for tests of the real binaries.
// Waiting uses a pidfd with poll(): no sleeps.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

extern char** environ;

namespace test_support {

class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& argv) {
    int err_pipe[2];
    if (pipe2(err_pipe, O_CLOEXEC) != 0) return;
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, err_pipe[1], STDERR_FILENO);
    posix_spawn_file_actions_adddup2(&fa, err_pipe[1], STDOUT_FILENO);
    std::vector<char*> args;
    for (const auto& a : argv)
      args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &fa, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
    close(err_pipe[1]);
    out_fd_ = err_pipe[0];
    if (pid_ > 0) pidfd_ = static_cast<int>(syscall(SYS_pidfd_open, pid_, 0));
  }
  ~ChildProcess() {
    if (pid_ > 0 && !exit_code_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) close(out_fd_);
    if (pidfd_ >= 0) close(pidfd_);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  [[nodiscard]] bool started() const { return pid_ > 0 && pidfd_ >= 0; }
  void signal(int sig) const { kill(pid_, sig); }

  // Exit code (128 + signal when killed), or nullopt if still running after `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    if (exit_code_) return exit_code_;
    pollfd p{pidfd_, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return std::nullopt;
    int status = 0;
    if (waitpid(pid_, &status, 0) != pid_) return std::nullopt;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return exit_code_;
  }

  // Everything the child wrote to stdout/stderr so far (call after wait() for all of it).
  std::string output() {
    char buf[4096];
    for (;;) {
      pollfd p{out_fd_, POLLIN, 0};
      if (poll(&p, 1, 0) <= 0) break;
      const ssize_t n = read(out_fd_, buf, sizeof(buf));
      if (n <= 0) break;
      out_.append(buf, static_cast<size_t>(n));
    }
    return out_;
  }

 private:
  pid_t pid_ = -1;
  int pidfd_ = -1;
  int out_fd_ = -1;
  std::optional<int> exit_code_;
  std::string out_;
};

// Runs a tool to completion: its exit code (-1 if it did not finish in `timeout`) and output.
struct ToolResult {
  int code = -1;
  std::string out;
};
inline ToolResult run_tool(const std::string& path, std::vector<std::string> args,
                           std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
  args.insert(args.begin(), path);
  ChildProcess p(args);
  if (!p.started()) return {};
  const auto code = p.wait(timeout);
  return {code.value_or(-1), p.output()};
}

}  // namespace test_support
