// Output name templates (farm/name_template.h): parsed once into literal and placeholder parts.
#include "farm/name_template.h"

#include <cctype>
#include <cstdio>

#include "core/error.h"

namespace stex::farm {

namespace {

[[noreturn]] void bad(const std::string& text, const std::string& why) {
  throw Error(ErrorKind::Usage, "bad output name template '" + text + "': " + why +
                                    " (placeholders: {tx} {ty} {index}, padded like {tx:03}, and <UDIM>)");
}

std::string padded(std::int64_t v, int pad) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%0*lld", pad, static_cast<long long>(v));
  return buf;
}

}  // namespace

int udim_number(int u, int v) {
  if (u < 0 || u >= 10)
    throw Error(ErrorKind::Usage,
                "<UDIM> needs tile column u < 10 (1001 + u + 10 v), got u = " + std::to_string(u));
  if (v < 0 || v > (2147483647 - 1010) / 10)
    throw Error(ErrorKind::Usage, "<UDIM> tile row v = " + std::to_string(v) + " is out of range");
  return 1001 + u + 10 * v;
}

NameTemplate::NameTemplate(std::string text) : text_(std::move(text)) {
  if (text_.empty()) throw Error(ErrorKind::Usage, "the output name is empty");
  std::string lit;
  auto flush = [&] {
    if (!lit.empty()) parts_.push_back({Kind::Literal, lit, 0});
    lit.clear();
  };
  for (std::size_t i = 0; i < text_.size();) {
    char c = text_[i];
    if (c == '{' && i + 1 < text_.size() && text_[i + 1] == '{') {
      lit += '{';
      i += 2;
    } else if (c == '}' && i + 1 < text_.size() && text_[i + 1] == '}') {
      lit += '}';
      i += 2;
    } else if (c == '}') {
      bad(text_, "unmatched '}' (write '}}' for a literal brace)");
    } else if (c == '{') {
      std::size_t close = text_.find('}', i);
      if (close == std::string::npos) bad(text_, "unmatched '{' (write '{{' for a literal brace)");
      std::string body = text_.substr(i + 1, close - i - 1);
      std::string name = body, fmt;
      std::size_t colon = body.find(':');
      if (colon != std::string::npos) {
        name = body.substr(0, colon);
        fmt = body.substr(colon + 1);
      }
      Part p{Kind::Literal, "", 0};
      if (name == "tx")
        p.kind = Kind::Tx;
      else if (name == "ty")
        p.kind = Kind::Ty;
      else if (name == "index")
        p.kind = Kind::Index;
      else
        bad(text_, "unknown placeholder '{" + body + "}'");
      if (colon != std::string::npos) {
        // Only zero padding: "0N" with N in 1..20 (a space-padded name would be a trap in shells).
        bool ok = fmt.size() >= 2 && fmt.size() <= 3 && fmt[0] == '0';
        for (std::size_t k = 1; ok && k < fmt.size(); ++k)
          ok = std::isdigit(static_cast<unsigned char>(fmt[k]));
        int width = ok ? std::stoi(fmt.substr(1)) : 0;
        if (!ok || width < 1 || width > 20)
          bad(text_, "bad padding in '{" + body + "}' (use a zero and a width from 1 to 20, like {tx:03})");
        p.pad = width;
      }
      flush();
      parts_.push_back(p);
      i = close + 1;
    } else if (c == '<') {
      std::size_t close = text_.find('>', i);
      std::string body = close == std::string::npos ? "" : text_.substr(i + 1, close - i - 1);
      bool tag = !body.empty();
      for (char b : body) tag = tag && (std::isalpha(static_cast<unsigned char>(b)) || b == '_');
      if (tag) {
        if (body != "UDIM") bad(text_, "unknown placeholder '<" + body + ">'");
        flush();
        parts_.push_back({Kind::Udim, "", 0});
        i = close + 1;
      } else {
        lit += c;
        ++i;
      }
    } else {
      lit += c;
      ++i;
    }
  }
  flush();
}

bool NameTemplate::has_placeholders() const {
  for (const Part& p : parts_)
    if (p.kind != Kind::Literal) return true;
  return false;
}

bool NameTemplate::uses_udim() const {
  for (const Part& p : parts_)
    if (p.kind == Kind::Udim) return true;
  return false;
}

void NameTemplate::check_grid(const TileGrid& grid) const {
  bool by_column = false, by_row = false;
  for (const Part& p : parts_) {
    by_column = by_column || p.kind == Kind::Tx || p.kind == Kind::Index || p.kind == Kind::Udim;
    by_row = by_row || p.kind == Kind::Ty || p.kind == Kind::Index || p.kind == Kind::Udim;
  }
  if (uses_udim() && grid.nx() > 10) {
    throw Error(ErrorKind::Usage,
                "output name '" + text_ +
                    "' uses <UDIM>, which allows at most 10 tiles per row (u < 10), but the grid has " +
                    grid.describe());
  }
  if ((grid.nx() > 1 && !by_column) || (grid.ny() > 1 && !by_row)) {
    throw Error(ErrorKind::Usage, "output name '" + text_ +
                                      "' gives several tiles the same name (the grid has " + grid.describe() +
                                      "): use {index}, <UDIM>, or both {tx} and {ty}");
  }
}

std::string NameTemplate::format(const TileRect& tile) const {
  std::string out;
  for (const Part& p : parts_) {
    switch (p.kind) {
      case Kind::Literal:
        out += p.literal;
        break;
      case Kind::Tx:
        out += padded(tile.tx, p.pad);
        break;
      case Kind::Ty:
        out += padded(tile.ty, p.pad);
        break;
      case Kind::Index:
        out += padded(tile.index, p.pad);
        break;
      case Kind::Udim:
        out += std::to_string(udim_number(tile.tx, tile.ty));
        break;
    }
  }
  return out;
}

}  // namespace stex::farm
