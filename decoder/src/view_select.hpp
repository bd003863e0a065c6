// SPDX-License-Identifier: MIT
// What a view asks of a node of the table (spec/format.md section 15.2's sphere and error
// bound): whether its sphere meets the view's frustum, how many pixels its error spans, and
// whether its normal cone faces away from the eye.
#pragma once
#include "pmz/decoder.hpp"
#include "pmz/node_table.hpp"

namespace pmz {

// The pixels node n's error bound spans on screen seen from `view` at the nearest point of its
// sphere (infinity with the eye inside the sphere), or -1 when the sphere lies wholly outside
// the frustum.
float projected_error(const View& view, const NodeEntry& n);

// Whether node n's normal cone (spec/format.md section 15.5) faces away from the eye wherever in
// its sphere its faces lie: then they all face away, and the view does not want n on its own
// merits. False for a node without a cone.
bool faces_away(const View& view, const NodeEntry& n);

}  // namespace pmz
