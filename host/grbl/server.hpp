// The byte pipes of `motionctl serve`: a pseudo-terminal that senders open as
// a serial port (LINK becomes a symlink to its slave side, e.g.
// /tmp/motioncore) and, optionally, TCP on 127.0.0.1 (bCNC's and UGS's
// socket://). Every byte read from either goes to one protocol Engine, and
// every reply goes to all of them. One thread, poll()-based.
//
// A sender that opens the PTY or connects gets the banner (Engine::greeting),
// as from a Grbl board whose port opening resets it: senders such as UGS wait
// for it to know the version. Replies left unread in the PTY by an earlier
// sender are dropped at that moment (the PTY's opens are seen with inotify).
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "host/grbl/protocol.hpp"

namespace mc::grbl {

struct ServerOptions {
  std::string pty_link;  // symlink to create (replaced if it is a symlink); empty: no PTY
  int tcp_port = -1;     // -1: no TCP; 0: any free port (tcp_port() tells which)
  int tick_ms = 2;       // the longest the loop sleeps before calling tick
};

class Server {
 public:
  // Opens the PTY and the listening socket; throws std::runtime_error naming
  // the call and the path or port that failed.
  Server(Engine& engine, const ServerOptions& options);
  // Closes everything and removes the symlink if it still points to our PTY.
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  const std::string& pty_path() const { return pty_path_; }  // "/dev/pts/N" or ""
  int tcp_port() const { return port_; }                     // -1 when none
  size_t tcp_clients() const { return clients_.size(); }

  // One round: waits at most tick_ms for input, reads it into the engine,
  // calls tick (the backend's chance to move), polls the engine and writes
  // its replies.
  void step(const std::function<void()>& tick);
  // Rounds until `stop` is set.
  void run(const std::atomic<bool>& stop, const std::function<void()>& tick);

 private:
  struct Pipe {
    int fd = -1;
    std::string out;  // replies not yet written
  };
  void close_all();
  void read_from(Pipe& p, bool& closed);
  void flush(Pipe& p, bool& closed);

  Engine& engine_;
  ServerOptions opt_;
  Pipe pty_;
  int pty_slave_ = -1;   // held open so the master never sees a hang-up between senders
  int inotify_fd_ = -1;  // IN_OPEN on the PTY's slave: a sender opened it
  std::string pty_path_;
  int listen_fd_ = -1;
  int port_ = -1;
  std::vector<Pipe> clients_;
};

// SIGINT and SIGTERM set the returned flag (handlers installed once).
const std::atomic<bool>& stop_on_signals();

// `motionctl serve` without the option parsing: the settings file read over
// the machine's defaults (and written back on every change), an Engine on
// `backend`, a Server, rounds until SIGINT/SIGTERM. `ready` is called once
// the PTY and the socket exist; returns the number of lines answered.
struct ServeConfig {
  ServerOptions server;
  std::string settings_path;
  Stored defaults;
};
uint64_t serve(Backend& backend, const ServeConfig& config, const std::function<void()>& tick,
               const std::function<void(const Server&)>& ready);

}  // namespace mc::grbl
