// Runs a piece of a test in a forked child whose files may not grow past a limit: a full disk
// without root and without filling any file system (issue 9, docs/reliability/soak_and_faults.md, "Faults").
#pragma once
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <functional>
#include <string>

namespace ridgeline::test {

/// Forks; the child sets RLIMIT_FSIZE to `limit` bytes with SIGXFSZ ignored (so write() fails
/// with EFBIG, as it fails with ENOSPC on a full disk), runs `body` and sends back the string it
/// returns, then leaves with _exit (no atexit handlers: gtest's, the leak checker's). Returns that
/// string, or "child died ..." when the child did not exit normally.
inline std::string in_child_with_file_limit(rlim_t limit,
                                            const std::function<std::string()>& body) {
  int fds[2];
  if (pipe(fds) != 0) return "pipe failed";
  const pid_t child = fork();
  if (child < 0) return "fork failed";
  if (child == 0) {
    close(fds[0]);
    signal(SIGXFSZ, SIG_IGN);
    rlimit r{};
    getrlimit(RLIMIT_FSIZE, &r);
    r.rlim_cur = limit;
    const std::string msg = setrlimit(RLIMIT_FSIZE, &r) == 0 ? body() : "setrlimit failed";
    for (std::size_t done = 0; done < msg.size();) {  // a pipe: the file limit does not apply
      const ssize_t n = write(fds[1], msg.data() + done, msg.size() - done);
      if (n <= 0) break;
      done += std::size_t(n);
    }
    _exit(0);
  }
  close(fds[1]);
  std::string msg;
  char buf[512];
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0;) msg.append(buf, std::size_t(n));
  close(fds[0]);
  int status = 0;
  waitpid(child, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return "child died (status " + std::to_string(status) + "): " + msg;
  return msg;
}

}  // namespace ridgeline::test
