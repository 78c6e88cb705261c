#pragma once
// The knot picker's grid (a dock of the window): the net's knots as discs in rows and columns,
// each filled with the colour of its label in the current camera and frame (as the views draw
// it; empty: no label, crossed: marked hidden), the knot to label ringed in blue, and the knots
// the colours of a junction fit (I) ringed in yellow, the one they identify in a thicker ring.
// Once a score exists, each knot's error against the simulation as a square behind its disc,
// green (0) through yellow to red (the largest, or 1 mm when all are smaller), the scale in a line
// below the grid and each knot's value in its tooltip. A click on a disc, or the arrow keys while
// the grid has the focus, picks the knot a click in a view labels next.

#include <QColor>
#include <QWidget>
#include <vector>

namespace netlab::gui {

class KnotGrid : public QWidget {
  Q_OBJECT

 public:
  struct Cell {
    QColor label;         // the label's colour; invalid: no label
    bool hidden = false;  // the person marked the knot hidden in this view
  };

  explicit KnotGrid(QWidget* parent = nullptr);

  void SetNet(int rows, int cols);  // forgets cells, offer and selection
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  // One cell per knot (row-major); a list of another size is ignored.
  void SetCells(std::vector<Cell> cells);
  void SetSelected(int knot);
  int selected() const { return selected_; }
  // The knots the colours offer (empty: none); `identified`: exactly one, identified.
  void SetOffered(std::vector<int> knots, bool identified);
  const std::vector<int>& offered() const { return offered_; }
  bool identified() const { return identified_; }
  // Each knot's error, mm (row-major; NaN: none), and what it is against ("RMS error against
  // sim.h5"); an empty list (or one of another size) shows none.
  void SetErrors(std::vector<double> errors_mm, QString source);
  const std::vector<double>& errors_mm() const { return errors_mm_; }
  // The colour of knot k's error (invalid: none shown), and of a fraction of the largest error.
  QColor ErrorColour(int knot) const;
  static QColor ErrorColour(double fraction);
  // The legend line below the grid ("" : no errors shown) and a knot's tooltip.
  QString ErrorLegend() const;
  QString KnotToolTip(int knot) const;

  // Knot k's disc centre in widget coordinates, and the knot under a point (-1: none).
  QPointF KnotCentre(int knot) const;
  int KnotAt(const QPointF& p) const;

  QSize sizeHint() const override { return {260, 260}; }
  QSize minimumSizeHint() const override { return {140, 140}; }

 signals:
  void knotPicked(int knot);

 protected:
  bool event(QEvent* event) override;  // arrows are the grid's own while it has the focus
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void keyPressEvent(QKeyEvent* event) override;

 private:
  // The grid's geometry in the widget: the spacing of the discs and the first disc's centre.
  double Pitch() const;
  double LegendHeight() const { return errors_mm_.empty() ? 0.0 : 16.0; }
  QPointF Origin() const;
  void Pick(int knot);

  int rows_ = 0, cols_ = 0;
  std::vector<Cell> cells_;
  int selected_ = -1;
  std::vector<int> offered_;
  bool identified_ = false;
  std::vector<double> errors_mm_;
  double worst_mm_ = 0.0;
  QString error_source_;
};

}  // namespace netlab::gui
