#include "text_table.hpp"

#include <algorithm>

namespace openvcu::cli {

std::size_t displayWidth(std::string_view text) noexcept {
  std::size_t width = 0;
  for (const char c : text) {
    if ((static_cast<unsigned char>(c) & 0xC0u) != 0x80u) ++width;  // not a continuation byte
  }
  return width;
}

TextTable::TextTable(std::vector<std::string> header) {
  m_rows.push_back(std::move(header));
}

void TextTable::addRow(std::vector<std::string> cells) {
  m_rows.push_back(std::move(cells));
}

void TextTable::appendTo(std::string& out, std::string_view indent) const {
  std::vector<std::size_t> widths;
  for (const auto& row : m_rows) {
    if (widths.size() < row.size()) widths.resize(row.size(), 0);
    for (std::size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], displayWidth(row[c]));
  }
  for (const auto& row : m_rows) {
    const std::size_t lineStart = out.size();
    out += indent;
    for (std::size_t c = 0; c < row.size(); ++c) {
      out += row[c];
      if (c + 1 < row.size()) out.append(widths[c] - displayWidth(row[c]) + 2, ' ');
    }
    while (out.size() > lineStart && out.back() == ' ') out.pop_back();
    out += '\n';
  }
}

}  // namespace openvcu::cli
