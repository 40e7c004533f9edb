#pragma once
// The recordings and uploaded logs vcu-web offers (docs/design/web.md, "Recordings"):
//
//   <dataFolder>/recordings/<name>/   folders written by `vcu record` (<bus>.log candump -L,
//                                     events.lcmlog) or by the HMI's Record button
//   <dataFolder>/uploads/<name>       logs uploaded from a browser (candump -L, candump, ASC)
//   <dataFolder>/cache/               archives and reports made for a request (removed after use
//                                     or when older than a day)
//
// Names in requests are single path components ([A-Za-z0-9._-], 1-128, not "." or "..");
// everything is resolved under the data folder and checked not to leave it (symlinks included).
//
//   web::DataFolder data("/var/lib/openvcu");
//   auto listing = data.listRecordings();            // newest first
//   auto archive = data.archiveRecording("drive1");  // cache/drive1-<random>.tar.gz
//   auto folder = data.recording("../etc");          // Error: "recording name '../etc': ..."

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::web {

struct RecordedFile {
  std::string name;  ///< "vehicle.log"
  std::uint64_t bytes{};
};

struct RecordingEntry {
  std::string name;                ///< the folder's (or uploaded file's) name
  std::uint64_t bytes{};           ///< total size
  std::int64_t modifiedUnixMs{};   ///< newest file's modification time
  std::vector<RecordedFile> files; ///< regular files only, sorted by name
};

/// True for a name a request may use: 1-128 of [A-Za-z0-9._-], not "." or "..", not starting with '.'.
[[nodiscard]] bool validEntryName(std::string_view name) noexcept;

/// @note thread-safe: no state but the folder path (methods touch only the file system).
class DataFolder {
 public:
  explicit DataFolder(std::filesystem::path root);
  /// Creates the data folder, recordings/, uploads/, uploads/.incoming and cache/ when missing
  /// (mode 0750); removes files older than a day from cache/ and uploads/.incoming (bodies of
  /// uploads that never finished). Error: a folder cannot be created or is not a folder.
  Status prepare() const;
  [[nodiscard]] const std::filesystem::path& root() const noexcept { return m_root; }

  /// Folders under recordings/, newest first. Unreadable entries are skipped.
  [[nodiscard]] std::vector<RecordingEntry> listRecordings() const;
  /// Files under uploads/, newest first.
  [[nodiscard]] std::vector<RecordingEntry> listUploads() const;
  /// The folder of recording `name`; error for a bad name or a missing folder.
  [[nodiscard]] Result<std::filesystem::path> recording(std::string_view name) const;
  /// The uploaded file `name`; error for a bad name or a missing file.
  [[nodiscard]] Result<std::filesystem::path> upload(std::string_view name) const;
  /// A gzip-compressed tar of recording `name` (its regular files, under "<name>/") written to
  /// a new file in cache/ with libarchive; the caller removes it after sending.
  /// @note blocks (reads the whole recording): call on a worker thread.
  [[nodiscard]] Result<std::filesystem::path> archiveRecording(std::string_view name) const;
  /// Moves a finished upload (a file in uploads/.incoming) to uploads/<name>; `name` is
  /// sanitised from the client's file name (other characters become '_'); an existing name
  /// gets "-2", "-3", ... Returns the final name.
  [[nodiscard]] Result<std::string> acceptUpload(const std::filesystem::path& incoming, std::string_view clientName) const;
  /// uploads/.incoming: where the HTTP server streams upload bodies.
  [[nodiscard]] std::filesystem::path incomingFolder() const;
  [[nodiscard]] std::filesystem::path cacheFolder() const;

 private:
  std::filesystem::path m_root;
};

}  // namespace openvcu::web
