#pragma once
// The line strips of the live plot (SignalPlot, CAN Data) and the trace timeline
// (TraceTimeline, Trace): one strip per series through each pixel column's low and high
// value, as trace::decimate() delivers them. Geometry nodes on OpenGL/RHI, a QPainter node
// on Qt Quick's software adaptation.
// @note render thread (updatePaintNode) only.

#include <QColor>
#include <QPolygonF>
#include <QQuickItem>
#include <QQuickWindow>
#include <QSGFlatColorMaterial>
#include <QSGGeometryNode>
#include <QSGRenderNode>
#include <QSGRendererInterface>
#include <cstddef>
#include <vector>

namespace openvcu::hmi {

/// Series in one plot or timeline.
constexpr std::size_t MAX_PLOT_SERIES = 4;
/// The colour of series i.
extern const QColor SERIES_COLOURS[MAX_PLOT_SERIES];
constexpr float LINE_MARGIN = 4;
constexpr float LINE_WIDTH = 2;

/// The plot lines where the scene graph has no graphics API (the software adaptation:
/// QT_QPA_PLATFORM=offscreen, QT_QUICK_BACKEND=software), which does not draw geometry
/// nodes: the same strips, painted with the QPainter the software renderer hands out.
class PainterLinesNode : public QSGRenderNode {
 public:
  explicit PainterLinesNode(QQuickWindow* window) : m_window(window) {}

  std::vector<QPolygonF> lines;  ///< one per series; resized in place, so no allocation once warm
  QRectF bounds;

  void render(const RenderState* state) override;
  [[nodiscard]] StateFlags changedStates() const override { return {}; }
  [[nodiscard]] RenderingFlags flags() const override { return BoundedRectRendering; }
  [[nodiscard]] QRectF rect() const override { return bounds; }

 private:
  QQuickWindow* m_window;
};

/// The scene-graph part of SignalPlot and TraceTimeline: `seriesCount` line strips through
/// each column's low and high value. `columns(i, base, span)` fills `scratch` with series
/// i's decimated columns (x, low, high) and returns how many; values map base..base+span to
/// the item's height. Geometry nodes (one per series, rebuilt when `rebuild`) on OpenGL/RHI,
/// a PainterLinesNode on the software adaptation.
template <typename Columns>
QSGNode* updateLines(QQuickItem& item, QSGNode* oldNode, bool& rebuild, std::size_t seriesCount,
                     const std::vector<float>& scratch, const Columns& columns) {
  const float h = static_cast<float>(item.height());
  const auto y = [h](float value, float base, float span) {
    return h - LINE_MARGIN - (value - base) / span * (h - 2 * LINE_MARGIN);
  };
  QQuickWindow* window = item.window();
  if (window != nullptr && window->rendererInterface()->graphicsApi() == QSGRendererInterface::Software) {
    auto* node = oldNode != nullptr ? static_cast<PainterLinesNode*>(oldNode) : new PainterLinesNode(window);
    node->bounds = QRectF(0, 0, item.width(), item.height());
    node->lines.resize(seriesCount);
    for (std::size_t i = 0; i < seriesCount; ++i) {
      float base = 0;
      float span = 1;
      const std::size_t filled = columns(i, base, span);
      QPolygonF& line = node->lines[i];
      line.resize(static_cast<qsizetype>(filled * 2));
      for (std::size_t c = 0; c < filled; ++c) {
        const auto x = static_cast<qreal>(scratch[c * 3]);
        line[static_cast<qsizetype>(c * 2)] = QPointF(x, y(scratch[c * 3 + 1], base, span));
        line[static_cast<qsizetype>(c * 2 + 1)] = QPointF(x, y(scratch[c * 3 + 2], base, span));
      }
    }
    node->markDirty(QSGNode::DirtyMaterial);
    rebuild = false;
    return node;
  }
  auto* root = oldNode != nullptr ? oldNode : new QSGNode;
  if (rebuild) {
    while (QSGNode* child = root->firstChild()) {
      root->removeChildNode(child);
      delete child;
    }
    for (std::size_t i = 0; i < seriesCount; ++i) {
      auto* node = new QSGGeometryNode;
      auto* geometry = new QSGGeometry(QSGGeometry::defaultAttributes_Point2D(), 0);
      geometry->setDrawingMode(QSGGeometry::DrawLineStrip);
      geometry->setLineWidth(LINE_WIDTH);
      node->setGeometry(geometry);
      node->setFlag(QSGNode::OwnsGeometry);
      auto* material = new QSGFlatColorMaterial;
      material->setColor(SERIES_COLOURS[i]);
      node->setMaterial(material);
      node->setFlag(QSGNode::OwnsMaterial);
      root->appendChildNode(node);
    }
    rebuild = false;
  }
  QSGNode* child = root->firstChild();
  for (std::size_t i = 0; i < seriesCount && child != nullptr; ++i, child = child->nextSibling()) {
    auto* node = static_cast<QSGGeometryNode*>(child);
    float base = 0;
    float span = 1;
    const std::size_t filled = columns(i, base, span);
    QSGGeometry* geometry = node->geometry();
    const int vertices = static_cast<int>(filled * 2);
    if (geometry->vertexCount() != vertices) geometry->allocate(vertices);
    QSGGeometry::Point2D* points = geometry->vertexDataAsPoint2D();
    for (std::size_t c = 0; c < filled; ++c) {
      points[c * 2].set(scratch[c * 3], y(scratch[c * 3 + 1], base, span));
      points[c * 2 + 1].set(scratch[c * 3], y(scratch[c * 3 + 2], base, span));
    }
    node->markDirty(QSGNode::DirtyGeometry);
  }
  return root;
}

}  // namespace openvcu::hmi
