#include "contact/qhull_facets.hpp"

#include <libqhull_r/qhull_ra.h>

#include <cstdio>
#include <cstdlib>

namespace manibench {
namespace scene_detail {

QhullStatus runQhull(const std::vector<double>& xyz, std::vector<QhullFacet>& facets,
                     std::string& message) {
  facets.clear();
  message.clear();
  const int count = static_cast<int>(xyz.size() / 3);
  if (count < 4) {
    message = "fewer than 4 points";
    return QhullStatus::Flat;
  }
  // Qhull reports through a FILE*; collect it in memory for the message.
  char* text = nullptr;
  std::size_t text_size = 0;
  FILE* err = open_memstream(&text, &text_size);

  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, err);
  // Default options merge coplanar facets (C-0); Qs searches all points for
  // the initial simplex, which is more robust for nearly flat input.
  char options[] = "qhull Qs";
  std::vector<double> points(xyz);  // Qhull wants a non-const array
  const int code = qh_new_qhull(qh, 3, count, points.data(), False, options, nullptr, err);
  if (code == qh_ERRnone) {
    facetT* facet;
    vertexT *vertex, **vertexp;
    FORALLfacets {
      QhullFacet out;
      for (int i = 0; i < 3; ++i) out.normal[i] = facet->normal[i];
      out.offset = -facet->offset;
      FOREACHvertex_(facet->vertices) out.points.push_back(qh_pointid(qh, vertex->point));
      facets.push_back(std::move(out));
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  std::fclose(err);
  if (text != nullptr) {
    message.assign(text, text_size);
    std::free(text);
  }
  if (code == qh_ERRnone) return QhullStatus::Ok;
  // Qhull's explanation is long; its first line says what went wrong.
  const std::size_t end = message.find('\n');
  if (end != std::string::npos) message.resize(end);
  // A flat input stops Qhull in one of two places: the initial simplex
  // (qh_ERRsingular) or, when every point shares one coordinate, the input
  // check (QH6013 "input is less than 3-dimensional", qh_ERRinput; a
  // PartNet cabinet's back panel modelled as one plane gives it).
  const bool flat = code == qh_ERRsingular ||
                    (code == qh_ERRinput && message.find("QH6013") != std::string::npos);
  return flat ? QhullStatus::Flat : QhullStatus::Failed;
}

}  // namespace scene_detail
}  // namespace manibench
