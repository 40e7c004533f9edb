#pragma once
// Aligned plain-text tables for human-readable output (`vcu dbc info`): columns padded to
// their widest cell (UTF-8 aware), two spaces between columns, no trailing blanks.
//
//   TextTable table({"ID", "NAME"});
//   table.addRow({"0x0CF004FE", "EEC1"});
//   table.appendTo(out, "  ");
//   -> "  ID          NAME\n  0x0CF004FE  EEC1\n"

#include <string>
#include <vector>

namespace openvcu::cli {

class TextTable {
 public:
  explicit TextTable(std::vector<std::string> header);

  /// Adds a row; missing cells are empty, extra cells are kept.
  void addRow(std::vector<std::string> cells);
  [[nodiscard]] bool empty() const noexcept { return m_rows.size() <= 1; }

  /// Appends the header and the rows, each line prefixed with `indent`.
  void appendTo(std::string& out, std::string_view indent = {}) const;

 private:
  std::vector<std::vector<std::string>> m_rows;  ///< the header first
};

/// Display width of UTF-8 text: code points, not bytes ("°C" is 2).
std::size_t displayWidth(std::string_view text) noexcept;

}  // namespace openvcu::cli
