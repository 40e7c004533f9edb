#include "common/plot_lines.hpp"

#include <QPainter>

namespace openvcu::hmi {

const QColor SERIES_COLOURS[MAX_PLOT_SERIES] = {QColor(0x42, 0xa5, 0xf5), QColor(0xff, 0xa7, 0x26),
                                                QColor(0x66, 0xbb, 0x6a), QColor(0xec, 0x40, 0x7a)};

void PainterLinesNode::render(const RenderState* state) {
  auto* painter = static_cast<QPainter*>(
      m_window->rendererInterface()->getResource(m_window, QSGRendererInterface::PainterResource));
  if (painter == nullptr) return;
  painter->save();
  if (const QRegion* clip = state->clipRegion(); clip != nullptr && !clip->isEmpty()) {
    painter->setClipRegion(*clip, Qt::ReplaceClip);  // before the transform
  }
  painter->setTransform(matrix()->toTransform());
  painter->setOpacity(inheritedOpacity());
  painter->setRenderHint(QPainter::Antialiasing, false);  // crisp and cheaper, as the GL lines
  for (std::size_t i = 0; i < lines.size(); ++i) {
    // a cosmetic 1-pixel pen: QPainter's stroker makes wider lines ~10x dearer in software
    QPen pen(SERIES_COLOURS[i], 0);
    pen.setCosmetic(true);
    painter->setPen(pen);
    painter->drawPolyline(lines[i]);
  }
  painter->restore();
}

}  // namespace openvcu::hmi
