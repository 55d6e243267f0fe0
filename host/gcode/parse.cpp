#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>

#include "host/gcode/block.hpp"

namespace mc::gcode {
namespace {

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

Error lex_error(int column, std::string word, int code, std::string message) {
  Error e;
  e.column = column;
  e.word = std::move(word);
  e.grbl_code = code;
  e.message = std::move(message);
  return e;
}

// Why a letter that is no word of this dialect is refused.
std::optional<std::string> refused_letter(char letter) {
  switch (letter) {
    case 'O':
      return "O-word subroutines and control flow are not supported";
    case 'A':
    case 'B':
    case 'C':
    case 'U':
    case 'V':
    case 'W':
      return "only the X, Y and Z axes exist on this machine";
    case 'D':
      return "cutter radius compensation (G41/G42 D) is not supported";
    case 'H':
      return "tool table offsets (G43 H) are not supported; use G43.1 Z";
    case 'E':
      return "E words (threading, analog outputs) are not supported";
    default:
      return std::nullopt;
  }
}

class Lexer {
 public:
  explicit Lexer(std::string_view text) : text_(text) {}

  ParsedLine run() {
    ParsedLine out;
    skip_blanks();
    if (at_end()) return out;
    if (text_[pos_] == '%') {
      ++pos_;
      skip_blanks_and_comments(out);
      if (!out.error && !at_end())
        out.error = lex_error(column(), "%", grbl::expected_command_letter,
                              "a '%' program delimiter must be alone on its line");
      out.block.percent = true;
      return out;
    }
    if (text_[pos_] == '/') {
      out.block.block_delete = true;
      ++pos_;
    }
    bool first_word = true;
    while (!out.error) {
      skip_blanks_and_comments(out);
      if (out.error || at_end()) break;
      word(out, first_word);
      first_word = false;
    }
    return out;
  }

 private:
  bool at_end() const { return pos_ >= text_.size(); }
  int column() const { return static_cast<int>(pos_) + 1; }
  void skip_blanks() {
    while (!at_end() && is_blank(text_[pos_])) ++pos_;
  }

  void skip_blanks_and_comments(ParsedLine& out) {
    for (;;) {
      skip_blanks();
      if (at_end()) return;
      const char c = text_[pos_];
      if (c == ';') {
        pos_ = text_.size();
        return;
      }
      if (c != '(') return;
      const int open = column();
      ++pos_;
      while (!at_end() && text_[pos_] != ')') {
        if (text_[pos_] == '(') {
          out.error = lex_error(column(), "(", grbl::expected_command_letter,
                                "nested comment: a comment started at column " + std::to_string(open) +
                                    " must be closed with ')' before another '('");
          return;
        }
        ++pos_;
      }
      if (at_end()) {
        out.error = lex_error(open, "(", grbl::expected_command_letter, "comment is not closed with ')'");
        return;
      }
      ++pos_;  // ')'
    }
  }

  // A decimal number, blanks allowed between its characters. Returns false
  // (and leaves pos_) when there is none.
  bool number(double& value, std::string& text) {
    size_t p = pos_;
    auto skip = [&] {
      while (p < text_.size() && is_blank(text_[p])) ++p;
    };
    std::string digits;
    skip();
    if (p < text_.size() && (text_[p] == '+' || text_[p] == '-')) {
      digits += text_[p++];
      skip();
    }
    bool any_digit = false;
    bool dot = false;
    while (p < text_.size()) {
      const char c = text_[p];
      if (std::isdigit(static_cast<unsigned char>(c)) != 0) {
        any_digit = true;
      } else if (c == '.' && !dot) {
        dot = true;
      } else if (!is_blank(c)) {
        break;
      }
      if (!is_blank(c)) digits += c;
      ++p;
    }
    if (!any_digit) return false;
    value = std::strtod(digits.c_str(), nullptr);
    text += digits;
    pos_ = p;
    return true;
  }

  void word(ParsedLine& out, bool first_word) {
    const int col = column();
    const char raw = text_[pos_];
    const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(raw)));
    if (raw == '#') {
      out.error = lex_error(col, "#", grbl::unsupported_command, "parameters (#) are not supported");
      return;
    }
    if (raw == '[') {
      out.error = lex_error(col, "[", grbl::unsupported_command, "expressions ([ ]) are not supported");
      return;
    }
    if (raw == '@' || raw == '^') {
      out.error = lex_error(col, std::string(1, raw), grbl::unsupported_command,
                            "polar coordinates (@ radius, ^ angle) are not supported");
      return;
    }
    if (letter < 'A' || letter > 'Z') {
      out.error = lex_error(col, std::string(1, raw), grbl::expected_command_letter,
                            std::string("expected a word (a letter and a number), found '") + raw + "'");
      return;
    }
    ++pos_;
    Word w;
    w.letter = letter;
    w.column = col;
    w.text = std::string(1, letter);
    if (auto why = refused_letter(letter)) {
      double ignored = 0;
      number(ignored, w.text);
      out.error = lex_error(col, w.text, grbl::unsupported_command, *why);
      return;
    }
    skip_blanks();
    if (!at_end() && (text_[pos_] == '#' || text_[pos_] == '[')) {
      const bool param = text_[pos_] == '#';
      out.error = lex_error(col, w.text + text_[pos_], grbl::unsupported_command,
                            param ? "parameters (#) are not supported: a word takes a plain number"
                                  : "expressions ([ ]) are not supported: a word takes a plain number");
      return;
    }
    if (!number(w.value, w.text)) {
      out.error = lex_error(col, w.text, grbl::bad_number_format,
                            std::string("expected a number after '") + letter + "'");
      return;
    }
    store(out, std::move(w), first_word);
  }

  static void store(ParsedLine& out, Word w, bool first_word) {
    Block& b = out.block;
    if (w.letter == 'G') {
      b.g.push_back(std::move(w));
      return;
    }
    if (w.letter == 'M') {
      b.m.push_back(std::move(w));
      return;
    }
    if (w.letter == 'N') {
      if (!first_word) {
        out.error = lex_error(w.column, w.text, grbl::invalid_line_number,
                              "a line number N must be the first word of the line");
        return;
      }
      if (w.value < 0 || w.value > 99999999 || w.value != std::floor(w.value)) {
        out.error = lex_error(w.column, w.text, grbl::invalid_line_number,
                              "a line number must be a whole number from 0 to 99999999");
        return;
      }
      b.n = std::move(w);
      return;
    }
    auto& slot = b.words.at(static_cast<size_t>(w.letter - 'A'));
    if (slot) {
      out.error =
          lex_error(w.column, w.text, grbl::word_repeated,
                    std::string("the ") + w.letter + " word is given twice on this line (first at column " +
                        std::to_string(slot->column) + ")");
      return;
    }
    slot = std::move(w);
  }

  std::string_view text_;
  size_t pos_ = 0;
};

}  // namespace

ParsedLine parse_line(std::string_view text) {
  return Lexer(text).run();
}

}  // namespace mc::gcode
