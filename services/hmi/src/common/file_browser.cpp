#include "common/file_browser.hpp"

#include <QDir>
#include <QFileInfo>
#include <algorithm>

#include "common/model_helpers.hpp"
#include "common/stack_connection.hpp"

namespace openvcu::hmi {
namespace {

QString sizeText(qint64 bytes) {
  if (bytes < 1024) return QStringLiteral("%1 B").arg(bytes);
  if (bytes < 1024 * 1024) return QStringLiteral("%1 kB").arg(static_cast<double>(bytes) / 1024.0, 0, 'f', 1);
  return QStringLiteral("%1 MB").arg(static_cast<double>(bytes) / (1024.0 * 1024.0), 0, 'f', 1);
}

}  // namespace

QString FileBrowserModel::defaultDataFolder() {
  if (StackConnection* stack = StackConnection::instance(); stack && !stack->settings().dataFolder.empty()) {
    return QDir::cleanPath(QDir::current().absoluteFilePath(QString::fromStdString(stack->settings().dataFolder)));
  }
  return QDir::cleanPath(QDir::homePath() + QStringLiteral("/openvcu"));
}

FileBrowserModel::FileBrowserModel(QObject* parent) : QAbstractListModel(parent), m_dataFolder(defaultDataFolder()) {
  setFolder(QDir(m_dataFolder).exists() ? m_dataFolder : QDir::currentPath());
}

int FileBrowserModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_entries.size());
}

QVariant FileBrowserModel::data(const QModelIndex& index, int role) const {
  const Entry* entry = rowAt(m_entries, index);
  if (!entry) return {};
  switch (role) {
    case NameRole:
    case Qt::DisplayRole:
      return entry->name;
    case PathRole:
      return entry->path;
    case IsFolderRole:
      return entry->folder;
    case SizeRole:
      return entry->folder ? QString() : sizeText(entry->size);
    case ModifiedRole:
      return entry->modified.isValid() ? entry->modified.toString(QStringLiteral("yyyy-MM-dd hh:mm")) : QString();
    default:
      return {};
  }
}

QHash<int, QByteArray> FileBrowserModel::roleNames() const {
  return {{NameRole, "name"}, {PathRole, "path"}, {IsFolderRole, "isFolder"}, {SizeRole, "sizeText"},
          {ModifiedRole, "modified"}};
}

void FileBrowserModel::setFolder(const QString& folder) {
  const QString cleaned = QDir::cleanPath(QDir::current().absoluteFilePath(folder));
  const QDir dir(cleaned);
  if (!dir.exists() || !dir.isReadable()) {
    m_error = QStringLiteral("%1: cannot be read").arg(cleaned);
    Q_EMIT folderChanged();
    return;
  }
  std::vector<Entry> entries;
  if (!dir.isRoot()) entries.push_back(Entry{QStringLiteral(".."), QFileInfo(cleaned).path(), true, 0, {}});
  const QFileInfoList infos =
      dir.entryInfoList(QDir::Dirs | QDir::Files | QDir::NoDotAndDotDot | QDir::Readable,
                        QDir::DirsFirst | QDir::Name | QDir::IgnoreCase);
  for (const QFileInfo& info : infos) {
    entries.push_back(Entry{info.fileName(), info.absoluteFilePath(), info.isDir(), info.size(), info.lastModified()});
  }
  beginResetModel();
  m_entries = std::move(entries);
  m_folder = cleaned;
  m_error.clear();
  endResetModel();
  Q_EMIT folderChanged();
}

QString FileBrowserModel::enter(int row) {
  if (row < 0 || row >= static_cast<int>(m_entries.size())) return {};
  const Entry entry = m_entries[static_cast<std::size_t>(row)];
  if (!entry.folder) return entry.path;
  setFolder(entry.path);
  return {};
}

void FileBrowserModel::up() { setFolder(QFileInfo(m_folder).path()); }

QString FileBrowserModel::newFilePath(const QString& name, const QString& extension) const {
  QDir().mkpath(m_dataFolder);  // a failure shows when the file is written (with the path)
  const QString stamp = QDateTime::currentDateTime().toString(QStringLiteral("yyyyMMdd-hhmmss"));
  return m_dataFolder + QLatin1Char('/') + name + QLatin1Char('-') + stamp + QLatin1Char('.') + extension;
}

}  // namespace openvcu::hmi
