#include "host/grbl/server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/inotify.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace mc::grbl {
namespace {

// Replies nobody reads (a PTY with no sender attached) are dropped past this.
constexpr size_t kMaxUnsent = size_t(1) << 16;

std::string sys_error(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

void set_nonblocking(int fd) {
  const int flags = ::fcntl(fd, F_GETFL);
  ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
}

std::atomic<bool> g_stop{false};

void on_signal(int) {
  g_stop.store(true);
}

}  // namespace

const std::atomic<bool>& stop_on_signals() {
  static const bool installed = [] {
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    ::sigaction(SIGINT, &sa, nullptr);
    ::sigaction(SIGTERM, &sa, nullptr);
    // A sender that disconnects mid-write must not kill the server.
    ::signal(SIGPIPE, SIG_IGN);
    return true;
  }();
  (void)installed;
  return g_stop;
}

Server::Server(Engine& engine, const ServerOptions& options) : engine_(engine), opt_(options) {
  if (!opt_.pty_link.empty()) {
    pty_.fd = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (pty_.fd < 0) throw std::runtime_error(sys_error("posix_openpt"));
    if (::grantpt(pty_.fd) != 0 || ::unlockpt(pty_.fd) != 0) {
      const std::string e = sys_error("grantpt/unlockpt");
      ::close(pty_.fd);
      throw std::runtime_error(e);
    }
    const char* name = ::ptsname(pty_.fd);
    pty_path_ = name ? name : "";
    pty_slave_ = pty_path_.empty() ? -1 : ::open(pty_path_.c_str(), O_RDWR | O_NOCTTY);
    if (pty_slave_ < 0) {
      const std::string e = sys_error("open " + pty_path_);
      ::close(pty_.fd);
      throw std::runtime_error(e);
    }
    // Raw bytes both ways: no echo, no line editing, no CR/LF mapping.
    termios tio{};
    ::tcgetattr(pty_slave_, &tio);
    ::cfmakeraw(&tio);
    ::tcsetattr(pty_slave_, TCSANOW, &tio);
    struct stat st {};
    if (::lstat(opt_.pty_link.c_str(), &st) == 0) {
      if (!S_ISLNK(st.st_mode)) {
        ::close(pty_slave_);
        ::close(pty_.fd);
        throw std::runtime_error("--pty " + opt_.pty_link + " exists and is not a symlink; not replacing it");
      }
      ::unlink(opt_.pty_link.c_str());
    }
    // Opens of the slave by anyone but us from now on; without inotify the
    // PTY works the same, only without the greeting.
    inotify_fd_ = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
    if (inotify_fd_ >= 0 && ::inotify_add_watch(inotify_fd_, pty_path_.c_str(), IN_OPEN) < 0) {
      ::close(inotify_fd_);
      inotify_fd_ = -1;
    }
    if (::symlink(pty_path_.c_str(), opt_.pty_link.c_str()) != 0) {
      const std::string e = sys_error("symlink " + opt_.pty_link + " -> " + pty_path_);
      ::close(pty_slave_);
      ::close(pty_.fd);
      throw std::runtime_error(e);
    }
  }
  // Whatever the engine said before the server existed (the power-up banner)
  // is for the PTY, which keeps it for the first sender; a TCP client gets
  // its own greeting when it connects.
  const std::string early = engine_.take_output();
  if (pty_.fd >= 0) pty_.out = early;
  if (opt_.tcp_port >= 0) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const int one = 1;
    ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(uint16_t(opt_.tcp_port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
        ::listen(listen_fd_, 4) != 0) {
      const std::string e = sys_error("listen on 127.0.0.1:" + std::to_string(opt_.tcp_port));
      close_all();
      throw std::runtime_error(e);
    }
    socklen_t len = sizeof addr;
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    set_nonblocking(listen_fd_);
  }
}

Server::~Server() {
  close_all();
}

void Server::close_all() {
  for (Pipe& c : clients_) ::close(c.fd);
  clients_.clear();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  if (!pty_path_.empty()) {
    char target[PATH_MAX];
    const ssize_t n = ::readlink(opt_.pty_link.c_str(), target, sizeof target - 1);
    if (n > 0 && std::string(target, size_t(n)) == pty_path_) ::unlink(opt_.pty_link.c_str());
    pty_path_.clear();
  }
  if (inotify_fd_ >= 0) ::close(inotify_fd_);
  inotify_fd_ = -1;
  if (pty_slave_ >= 0) ::close(pty_slave_);
  pty_slave_ = -1;
  if (pty_.fd >= 0) ::close(pty_.fd);
  pty_.fd = -1;
}

void Server::read_from(Pipe& p, bool& closed) {
  char buf[512];
  while (engine_.input_room() > 0) {
    const ssize_t n = ::read(p.fd, buf, std::min(sizeof buf, engine_.input_room()));
    if (n > 0) {
      engine_.receive(std::string_view(buf, size_t(n)));
      continue;
    }
    if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != EIO)) closed = true;
    return;
  }
}

void Server::flush(Pipe& p, bool& closed) {
  while (!p.out.empty()) {
    const ssize_t n = ::write(p.fd, p.out.data(), p.out.size());
    if (n > 0) {
      p.out.erase(0, size_t(n));
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) closed = true;
    break;
  }
  if (p.out.size() > kMaxUnsent) p.out.clear();
}

void Server::step(const std::function<void()>& tick) {
  // Stop reading senders while the engine has no room: the kernel buffers,
  // the sender waits, nothing is dropped.
  const short in = engine_.input_room() > 0 ? POLLIN : 0;
  std::vector<pollfd> fds;
  if (pty_.fd >= 0) fds.push_back({pty_.fd, short(in | (pty_.out.empty() ? 0 : POLLOUT)), 0});
  if (listen_fd_ >= 0) fds.push_back({listen_fd_, POLLIN, 0});
  if (inotify_fd_ >= 0) fds.push_back({inotify_fd_, POLLIN, 0});
  for (const Pipe& c : clients_) fds.push_back({c.fd, short(in | (c.out.empty() ? 0 : POLLOUT)), 0});
  ::poll(fds.data(), fds.size(), opt_.tick_ms);

  bool closed = false;
  if (inotify_fd_ >= 0) {
    alignas(inotify_event) char ev[4096];
    bool opened = false;
    while (::read(inotify_fd_, ev, sizeof ev) > 0) opened = true;
    if (opened) {
      // A new sender: what an earlier one left unread is not for it.
      ::tcflush(pty_slave_, TCIFLUSH);
      pty_.out = engine_.greeting();
    }
  }
  if (pty_.fd >= 0) read_from(pty_, closed);  // a PTY never closes: our slave fd keeps it open
  if (listen_fd_ >= 0) {
    for (;;) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) break;
      clients_.push_back(Pipe{fd, engine_.greeting()});
    }
  }
  std::vector<bool> gone(clients_.size(), false);
  for (size_t i = 0; i < clients_.size(); ++i) {
    bool c = false;
    read_from(clients_[i], c);
    gone[i] = c;
  }
  if (tick) tick();
  engine_.poll();
  const std::string out = engine_.take_output();
  if (pty_.fd >= 0) {
    pty_.out += out;
    flush(pty_, closed);
  }
  for (size_t i = 0; i < clients_.size(); ++i) {
    clients_[i].out += out;
    bool c = false;
    flush(clients_[i], c);
    gone[i] = gone[i] || c;
  }
  for (size_t i = clients_.size(); i-- > 0;)
    if (gone[i]) {
      ::close(clients_[i].fd);
      clients_.erase(clients_.begin() + long(i));
    }
}

void Server::run(const std::atomic<bool>& stop, const std::function<void()>& tick) {
  while (!stop.load()) step(tick);
}

uint64_t serve(Backend& backend, const ServeConfig& config, const std::function<void()>& tick,
               const std::function<void(const Server&)>& ready) {
  EngineOptions eo;
  eo.defaults = config.defaults;
  eo.stored = load_stored(config.settings_path, config.defaults);
  const std::string path = config.settings_path;
  eo.save = [path](const Stored& s) { save_stored(path, s); };
  const std::atomic<bool>& stop = stop_on_signals();
  Engine engine(backend, std::move(eo));
  Server server(engine, config.server);
  if (ready) ready(server);
  server.run(stop, tick);
  return engine.lines_answered();
}

}  // namespace mc::grbl
