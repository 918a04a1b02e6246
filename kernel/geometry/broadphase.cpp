#include "limber/kernel/geometry/broadphase.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

namespace limber {
namespace {

// Cell indices are clamped to ±2³⁰ (a box 10⁹ cells from the origin shares the last cell with
// its neighbours there: still correct, only slower), so a cell's two indices pack in 64 bits.
constexpr std::int64_t kCellLimit = std::int64_t(1) << 30;
// Most grid entries per box, all boxes together: wider cells beyond.
constexpr double kMostEntriesPerBox = 4;

}  // namespace

std::int64_t SweepAndPrune::cell_index(double coordinate, int k) const {
  const double width = grid_.width[k];
  if (!(width < std::numeric_limits<double>::infinity())) return 0;
  const double cell = std::floor(coordinate / width);
  return static_cast<std::int64_t>(std::clamp(cell, double(-kCellLimit), double(kCellLimit)));
}

std::uint64_t SweepAndPrune::cell_key(std::int64_t a, std::int64_t b) const {
  return (static_cast<std::uint64_t>(a + kCellLimit) << 32) | static_cast<std::uint64_t>(b + kCellLimit);
}

bool SweepAndPrune::choose_grid(std::initializer_list<std::span<const Aabb>> sets) {
  // The sweep axis: where the centres vary most (n² × variance, without the division).
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum_of_squares = Eigen::Vector3d::Zero(), extent = Eigen::Vector3d::Zero();
  std::size_t count = 0;
  for (const std::span<const Aabb> boxes : sets) {
    for (const Aabb& box : boxes) {
      const Eigen::Vector3d centre = 0.5 * (box.min + box.max);
      sum += centre;
      sum_of_squares += centre.cwiseProduct(centre);
      extent += box.max - box.min;
    }
    count += boxes.size();
  }
  const double n = static_cast<double>(count);
  const Eigen::Vector3d spread = n * sum_of_squares - sum.cwiseProduct(sum);
  int axis = 0;
  if (count >= 2) {
    for (int k = 1; k < 3; ++k) {
      if (spread[k] > spread[axis]) axis = k;
    }
  }
  // Cells twice the mean extent along the other two axes (one cell where that is 0). The last
  // call's cells stay while the axes do and the extents are within a factor two of those they
  // were chosen for, so the last order stays meaningful.
  Grid grid;
  grid.axis = axis;
  for (int c = 0, k = 0; k < 3; ++k) {
    if (k == axis) continue;
    const double width = count > 0 ? 2 * extent[k] / n : 0.0;
    grid.cell_axes[c] = k;
    grid.basis[c] = width > 0 && std::isfinite(width) ? width : std::numeric_limits<double>::infinity();
    ++c;
  }
  const auto fits = [](double now, double then) { return now == then || (now >= 0.5 * then && now <= 2 * then); };
  bool coherent = grid.axis == grid_.axis;
  for (int c = 0; c < 2; ++c) coherent = coherent && grid.cell_axes[c] == grid_.cell_axes[c] && fits(grid.basis[c], grid_.basis[c]);
  for (int c = 0; c < 2; ++c) grid.width[c] = coherent ? grid_.width[c] : grid.basis[c];
  grid_ = grid;
  // At most kMostEntriesPerBox entries a box: a few large boxes among small ones widen the cells.
  for (;;) {
    double entries = 0;
    for (const std::span<const Aabb> boxes : sets) {
      for (const Aabb& box : boxes) {
        entries += double(cell_index(box.max[grid_.cell_axes[0]], 0) - cell_index(box.min[grid_.cell_axes[0]], 0) + 1) *
                   double(cell_index(box.max[grid_.cell_axes[1]], 1) - cell_index(box.min[grid_.cell_axes[1]], 1) + 1);
      }
    }
    if (entries <= kMostEntriesPerBox * n) break;
    grid_.width[0] *= 2, grid_.width[1] *= 2;
    coherent = false;
  }
  return coherent;
}

void SweepAndPrune::sort_entries(Sorted& sorted, std::span<const Aabb> boxes, bool coherent) const {
  const int axis = grid_.axis, k0 = grid_.cell_axes[0], k1 = grid_.cell_axes[1];
  const bool from_last = coherent && sorted.cells.size() == boxes.size();
  std::swap(sorted.cells, sorted.previous_cells);
  sorted.cells.resize(boxes.size());
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    sorted.cells[b] = {{cell_index(boxes[b].min[k0], 0), cell_index(boxes[b].min[k1], 1)},
                       {cell_index(boxes[b].max[k0], 0), cell_index(boxes[b].max[k1], 1)}};
  }
  const auto reaches = [](const CellRange& range, std::int64_t i, std::int64_t j) {
    return range.low[0] <= i && i <= range.high[0] && range.low[1] <= j && j <= range.high[1];
  };
  // Box b's entries in the cells it reaches, but those `skip` reaches, appended to `out`.
  const auto add_entries = [&](std::uint32_t b, std::vector<Entry>& out, const CellRange* skip) {
    const CellRange& range = sorted.cells[b];
    for (std::int64_t i = range.low[0]; i <= range.high[0]; ++i) {
      for (std::int64_t j = range.low[1]; j <= range.high[1]; ++j) {
        if (!skip || !reaches(*skip, i, j)) out.push_back({cell_key(i, j), boxes[b].min[axis], boxes[b].max[axis], b});
      }
    }
  };
  const auto before = [](const Entry& a, const Entry& b) {
    if (a.cell != b.cell) return a.cell < b.cell;
    return a.min < b.min || (a.min == b.min && a.box < b.box);
  };
  std::vector<Entry>& entries = sorted.entries;
  std::size_t adding = 0;  // entries in cells the boxes newly reach
  if (from_last) {
    for (std::uint32_t b = 0; b < boxes.size(); ++b) {
      if (sorted.cells[b] == sorted.previous_cells[b]) continue;
      const CellRange& range = sorted.cells[b];
      for (std::int64_t i = range.low[0]; i <= range.high[0]; ++i) {
        for (std::int64_t j = range.low[1]; j <= range.high[1]; ++j) adding += !reaches(sorted.previous_cells[b], i, j);
      }
    }
  }
  if (!from_last || adding > sorted.added.capacity()) {
    // Anew. Room for the most entries there can be (kMostEntriesPerBox a box), and for a quarter of
    // them arriving in new cells in one call: later calls allocate nothing (the pages stay
    // untouched until used).
    entries.clear();
    entries.reserve(static_cast<std::size_t>(kMostEntriesPerBox) * boxes.size());
    for (std::uint32_t b = 0; b < boxes.size(); ++b) add_entries(b, entries, nullptr);
    std::sort(entries.begin(), entries.end(), before);
    sorted.added.reserve(entries.capacity() / 4);
    sorted.previous_cells.reserve(sorted.cells.capacity());
    return;
  }
  // Last call's entries in last call's order, those whose box still reaches their cell, with
  // the box's interval now: nearly sorted, so insertion sort...
  std::size_t kept = 0;
  for (const Entry& entry : entries) {
    const std::int64_t i = static_cast<std::int64_t>(entry.cell >> 32) - kCellLimit;
    const std::int64_t j = static_cast<std::int64_t>(entry.cell & 0xFFFFFFFFu) - kCellLimit;
    if (reaches(sorted.cells[entry.box], i, j)) {
      entries[kept++] = {entry.cell, boxes[entry.box].min[axis], boxes[entry.box].max[axis], entry.box};
    }
  }
  entries.resize(kept);
  for (std::size_t i = 1; i < entries.size(); ++i) {
    const Entry moving = entries[i];
    std::size_t j = i;
    for (; j > 0 && before(moving, entries[j - 1]); --j) entries[j] = entries[j - 1];
    entries[j] = moving;
  }
  // ...then the entries of the cells boxes newly reach, sorted and merged in from the back.
  if (adding == 0) return;
  sorted.added.clear();
  for (std::uint32_t b = 0; b < boxes.size(); ++b) {
    if (!(sorted.cells[b] == sorted.previous_cells[b])) add_entries(b, sorted.added, &sorted.previous_cells[b]);
  }
  std::sort(sorted.added.begin(), sorted.added.end(), before);
  entries.resize(kept + adding);
  std::size_t from = kept, next = adding, to = kept + adding;
  while (next > 0) {
    if (from > 0 && before(sorted.added[next - 1], entries[from - 1])) {
      entries[--to] = entries[--from];
    } else {
      entries[--to] = sorted.added[--next];
    }
  }
}

const std::vector<CandidatePair>& SweepAndPrune::find_pairs(std::span<const Aabb> boxes) {
  pairs_.clear();
  sort_entries(first_, boxes, choose_grid({boxes}));

  // Sweep each cell: a box meets the boxes after it in the cell that start before it ends (ties
  // in min included, as touching counts); those are checked on all three axes, and a pair is
  // kept in the first cell the two share.
  const std::vector<Entry>& entries = first_.entries;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Entry& current = entries[i];
    std::size_t j = i + 1;
    for (; j < entries.size() && entries[j].cell == current.cell && entries[j].min <= current.max; ++j) {
      const std::uint32_t a = current.box, b = entries[j].box;
      if (!overlaps(boxes[a], boxes[b])) continue;
      if (first_shared_cell(first_.cells[a], first_.cells[b]) != current.cell) continue;
      pairs_.emplace_back(std::min(a, b), std::max(a, b));
    }
    comparisons_ += j - i - 1;
  }
  std::sort(pairs_.begin(), pairs_.end());
  return pairs_;
}

const std::vector<CandidatePair>& SweepAndPrune::find_pairs_between(std::span<const Aabb> first,
                                                                    std::span<const Aabb> second) {
  pairs_.clear();
  const bool coherent = choose_grid({first, second});
  sort_entries(first_, first, coherent);
  sort_entries(second_, second, coherent);

  // Cell by cell, a pair overlapping on the axis is found from the box that starts first (a tie:
  // from the first set's): each entry of one set walks the other set's entries that start
  // within it.
  const auto sweep = [&](const Sorted& walkers, const Sorted& others, bool walkers_first) {
    std::size_t start = 0;
    for (const Entry& current : walkers.entries) {
      // Skip the others before it (or, walking the second set, level with it): theirs to find.
      while (start < others.entries.size()) {
        const Entry& other = others.entries[start];
        const bool behind = other.cell < current.cell ||
                            (other.cell == current.cell && (other.min < current.min || (!walkers_first && other.min == current.min)));
        if (!behind) break;
        ++start;
      }
      std::size_t j = start;
      for (; j < others.entries.size() && others.entries[j].cell == current.cell && others.entries[j].min <= current.max; ++j) {
        const std::uint32_t a = walkers_first ? current.box : others.entries[j].box;
        const std::uint32_t b = walkers_first ? others.entries[j].box : current.box;
        if (!overlaps(first[a], second[b])) continue;
        if (first_shared_cell(first_.cells[a], second_.cells[b]) != current.cell) continue;
        pairs_.emplace_back(a, b);
      }
      comparisons_ += j - start;
    }
  };
  sweep(first_, second_, true);
  sweep(second_, first_, false);
  std::sort(pairs_.begin(), pairs_.end());
  return pairs_;
}

std::uint64_t SweepAndPrune::first_shared_cell(const CellRange& a, const CellRange& b) const {
  return cell_key(std::max(a.low[0], b.low[0]), std::max(a.low[1], b.low[1]));
}

void SweepAndPrune::reserve(std::size_t boxes, std::size_t second_boxes, std::size_t pairs) {
  for (const auto& [sorted, count] : {std::pair{&first_, boxes}, std::pair{&second_, second_boxes}}) {
    sorted->entries.reserve(static_cast<std::size_t>(kMostEntriesPerBox) * count);
    sorted->added.reserve(count);
    sorted->cells.reserve(count);
    sorted->previous_cells.reserve(count);
  }
  pairs_.reserve(pairs);
}

std::size_t SweepAndPrune::reserved_bytes() const {
  std::size_t bytes = pairs_.capacity() * sizeof(CandidatePair);
  for (const Sorted* sorted : {&first_, &second_}) {
    bytes += (sorted->entries.capacity() + sorted->added.capacity()) * sizeof(Entry) +
             (sorted->cells.capacity() + sorted->previous_cells.capacity()) * sizeof(CellRange);
  }
  return bytes;
}

std::span<Aabb> BallCandidates::boxes(std::size_t shapes, std::size_t balls) {
  shapes_ = shapes;
  balls_ = balls;
  list_every_ = reference_ || balls < kSearchFromBalls;
  boxes_.resize(list_every_ ? 0 : shapes + balls);
  return boxes_;
}

void BallCandidates::find(bool other_balls) {
  // A body gone non-finite (a NaN world) has no box to sort: every ball then gets every body this
  // call, and the exact tests refuse what is not finite.
  list_every_ = list_every_ || !std::all_of(boxes_.begin(), boxes_.end(), [](const Aabb& box) {
    return box.min.allFinite() && box.max.allFinite();
  });
  if (list_every_) {
    // Every ball every body (itself too: the callers skip it), one list shared by all.
    listed_count_ = shapes_ + (other_balls ? balls_ : 0);
    if (every_.size() < listed_count_) {
      const std::size_t held = every_.size();
      every_.resize(listed_count_);
      for (std::size_t k = held; k < every_.size(); ++k) every_[k] = static_cast<std::uint32_t>(k);
    }
    listed_ += balls_ * listed_count_;
    return;
  }
  // The callers' sphere tests compute their distances otherwise than these bounds: each box is
  // grown by far more than either's round-off, 1e-9 of its largest coordinate.
  for (Aabb& box : boxes_) {
    const double slack = 1e-9 * std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
    box.min.array() -= slack;
    box.max.array() += slack;
  }
  const std::span<const Aabb> all(boxes_);
  const std::span<const Aabb> shapes = all.first(shapes_), balls = all.subspan(shapes_);
  const std::vector<CandidatePair>& across = across_.find_pairs_between(shapes, balls);
  const std::vector<CandidatePair>* among = other_balls ? &among_.find_pairs(balls) : nullptr;
  // Lists by counting sort, each ball's in increasing order: the pairs come sorted, shapes
  // (first of their pairs) before balls, and a ball's pairs (p, b) with a lower ball p before
  // its pairs (b, q) with a higher one.
  begin_.assign(balls.size() + 1, 0);
  for (const CandidatePair& pair : across) ++begin_[pair.second + 1];
  if (among) {
    for (const CandidatePair& pair : *among) ++begin_[pair.first + 1], ++begin_[pair.second + 1];
  }
  for (std::size_t b = 0; b < balls.size(); ++b) begin_[b + 1] += begin_[b];
  candidates_.resize(begin_.back());
  for (const CandidatePair& pair : across) candidates_[begin_[pair.second]++] = pair.first;
  if (among) {
    const auto shapes_count = static_cast<std::uint32_t>(shapes_);
    for (const CandidatePair& pair : *among) {
      candidates_[begin_[pair.first]++] = shapes_count + pair.second;
      candidates_[begin_[pair.second]++] = shapes_count + pair.first;
    }
  }
  // Each begin_ now holds the next ball's start: shift back.
  for (std::size_t b = balls.size(); b > 0; --b) begin_[b] = begin_[b - 1];
  begin_[0] = 0;
}

void BallCandidates::reserve(std::size_t shapes, std::size_t balls, std::size_t candidates) {
  across_.reserve(shapes, balls, candidates);
  among_.reserve(balls, 0, candidates);
  boxes_.reserve(shapes + balls);
  begin_.reserve(balls + 1);
  candidates_.reserve(candidates);
}

std::size_t BallCandidates::reserved_bytes() const {
  return across_.reserved_bytes() + among_.reserved_bytes() + boxes_.capacity() * sizeof(Aabb) +
         (begin_.capacity() + candidates_.capacity() + every_.capacity()) * sizeof(std::uint32_t);
}

std::vector<CandidatePair> brute_force_pairs(std::span<const Aabb> boxes) {
  std::vector<CandidatePair> pairs;
  for (std::uint32_t i = 0; i < boxes.size(); ++i) {
    for (std::uint32_t j = i + 1; j < boxes.size(); ++j) {
      if (overlaps(boxes[i], boxes[j])) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

std::vector<CandidatePair> brute_force_pairs_between(std::span<const Aabb> first, std::span<const Aabb> second) {
  std::vector<CandidatePair> pairs;
  for (std::uint32_t i = 0; i < first.size(); ++i) {
    for (std::uint32_t j = 0; j < second.size(); ++j) {
      if (overlaps(first[i], second[j])) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

}  // namespace limber
