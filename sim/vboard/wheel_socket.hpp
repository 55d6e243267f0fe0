// The virtual board's handwheel, turned from another process: a Unix-domain
// socket the server (`motionctl sim serve`) listens on beside its state
// file, and the client `motionctl sim wheel` speaks to it. The protocol is
// one line each way:
//
//   client: "wheel DETENTS SECONDS\n"   (VirtualBoard::turn_handwheel's arguments)
//   server: "ok\n" once the turn is done in board time, or "error: WHAT\n" at once
//
// The server answers only after the last edge, so a client that goes on to
// read the board sees the whole turn counted (the motion it starts may
// still be running).
//
//   WheelSocket ws(path);            // server: bound and listening
//   ws.serve(board);                 // between runs: takes requests, answers finished turns
//   request_wheel_turn(path, 5, 1);  // client: returns when the turn is done
#pragma once

#include <string>
#include <vector>

namespace mc::sim {

class VirtualBoard;

class WheelSocket {
 public:
  // Binds and listens at `path`, replacing a socket a dead server left
  // there; throws std::runtime_error naming the path and the failing call.
  explicit WheelSocket(std::string path);
  ~WheelSocket();  // closes every connection and removes the socket file
  WheelSocket(const WheelSocket&) = delete;
  WheelSocket& operator=(const WheelSocket&) = delete;

  const std::string& path() const { return path_; }
  int fd() const { return fd_; }  // readable when a client connects
  // Accepts the clients waiting, starts their turns on `board`, and answers
  // those whose turn the board's clock has passed. Returns whether a
  // request came (the host is active). Never blocks longer than a client
  // takes to send its line (at most 100 ms).
  bool serve(VirtualBoard& board);
  // A client waits for its turn to end: the board must keep running.
  bool waiting() const { return !waiting_.empty(); }

 private:
  struct Waiting {
    int fd;
    double done_s;  // board time at which its turn is done
  };
  std::string path_;
  int fd_ = -1;
  std::vector<Waiting> waiting_;
};

// Asks the server at `path` to turn the wheel and waits for its answer.
// Throws std::runtime_error when nothing listens there, or with the
// server's words when it refuses the turn.
void request_wheel_turn(const std::string& path, int detents, double seconds);

}  // namespace mc::sim
