"""Step 7b: limb ends modelled as small pieces (units: mm).

A joined piece too small to get bones of its own (``assemble``: under ``BIG_PIECE`` of the
body's volume, ``LIMB_SIZE`` / ``CLOSED_LIMB_SIZE`` of the model's size) takes the weights of
the body next to it, and the thin-branch step (``thin``) never sees it: it works on one rigged
piece at a time. On low-poly figures such pieces are often the ends of limbs: RigNet 1347's
hands are three open 8-vertex boxes each (5.4 x 9 x 5.4 mm) glued under the end of its closed
arm pieces, 7.7 mm past the arm's last vertex, and the bench's extremity measure missed all six
hand ends by 4.4-8.1 limb radii (issue 35). Each such piece is tested as a thin branch would
be, on the union of the pieces:

* the piece must be a solid: closed, or its holes closed by ``pieces.cap_holes`` (a sheet is
  not a limb);
* b: the bone most of its vertices are bound to (the weights copied from the body); c: its
  vertex farthest from b; q: the nearest point of b to c;
* the straight line from c to q stays inside the union of the piece and the rigged pieces
  (inner radius > 0 at 32 samples, the inner radius of the union being the largest of the
  pieces' own: each piece is closed, so a point inside one is inside the union);
* the part of it beyond the limb's surface (length L = |c - q| - the inner radius at q) is
  longer than ``spur`` x its width (2 x the largest inner radius along that part) and that
  width is at least ``min_thickness`` (printable), as for a thin branch;
* no bone ends within that width of c;
* the piece is not a flat plate there: its vertices less than L / 2 in from c along the line
  lie within L / (2 ``spur``) of the line through their own centroid parallel to it (a
  finger's outer half; the rim of a plate is as broad as the plate);

then a bone runs from q (a child of b) to the first point in from c that is ``END_RATIO``
radii from c and printable (``thin._tail``), and the piece's vertices nearer that bone than b
go to it (weight 1)."""
