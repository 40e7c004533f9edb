#pragma once
// A folder listing for touch screens (the trace viewer's "Browse", no desktop file dialog on
// the VCU) and the HMI's data folder, where exports go (--data-folder, default
// $HOME/openvcu). Folders first, then files, each sorted by name; ".." is a row.
//
//   FileBrowserModel { id: browser }                 // starts in the data folder
//   onClicked: { const file = browser.enter(index); if (file !== "") trace.open(file) }
//   logModel.exportTo(browser.newFilePath("vcu-hmi-log", "txt"))

#include <QAbstractListModel>
#include <QDateTime>
#include <QQmlEngine>
#include <QString>
#include <vector>

namespace openvcu::hmi {

class FileBrowserModel : public QAbstractListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString folder READ folder WRITE setFolder NOTIFY folderChanged)
  Q_PROPERTY(QString dataFolder READ dataFolder CONSTANT)
  Q_PROPERTY(QString errorString READ errorString NOTIFY folderChanged)
 public:
  enum Role { NameRole = Qt::UserRole + 1, PathRole, IsFolderRole, SizeRole, ModifiedRole };
  explicit FileBrowserModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;

  [[nodiscard]] QString folder() const { return m_folder; }
  /// Lists `folder` (absolute, cleaned); a folder that cannot be read keeps the previous
  /// listing and sets errorString.
  void setFolder(const QString& folder);
  [[nodiscard]] QString dataFolder() const { return m_dataFolder; }
  [[nodiscard]] QString errorString() const { return m_error; }
  /// A folder row: lists it and returns "". A file row: returns its absolute path.
  Q_INVOKABLE QString enter(int row);
  Q_INVOKABLE void up();
  Q_INVOKABLE void reload() { setFolder(m_folder); }
  /// DATA/NAME-yyyyMMdd-hhmmss.EXT in the data folder, which is created when missing.
  Q_INVOKABLE QString newFilePath(const QString& name, const QString& extension) const;
  /// The data folder of the running HMI: --data-folder, else $HOME/openvcu.
  static QString defaultDataFolder();

 Q_SIGNALS:
  void folderChanged();

 private:
  struct Entry {
    QString name;
    QString path;
    bool folder{};
    qint64 size{};
    QDateTime modified;
  };
  QString m_folder;
  QString m_dataFolder;
  QString m_error;
  std::vector<Entry> m_entries;
};

}  // namespace openvcu::hmi
