# cython: language_level=3, boundscheck=False, wraparound=False, initializedcheck=False, nonecheck=False,
# cython: cdivision=True
"""The camera's per-pixel z-buffer loop for vertical cylinders, compiled (optional: see ``zbuffer.py``).

``camera._draw_circles`` computes, with numpy, everything per column for all cylinders at once (where each
ray enters and leaves, the face colour); what is left is a loop over each cylinder's band of rows and
columns: depth test, write. numpy pays a dozen calls per cylinder for it (or, batched, a dozen arrays
as long as all the bands together); here it is one pass, with the same float32 arithmetic in the same
order, so the pixels are bit for bit those of the numpy path (a test renders both ways).
"""


def draw_cylinders(float[:, ::1] disparity not None, unsigned char[:, :, ::1] image not None,
                   short[:, ::1] labels,
                   const float[::1] t1 not None, const float[::1] t2 not None,
                   const unsigned char[:, ::1] face not None,
                   const float[::1] lo_rows not None, const float[::1] hi_rows not None,
                   const Py_ssize_t[::1] start not None, const Py_ssize_t[::1] u0 not None,
                   const Py_ssize_t[::1] ncols not None, const Py_ssize_t[::1] v0 not None,
                   const Py_ssize_t[::1] v1 not None, const Py_ssize_t[::1] limit_row0 not None,
                   const unsigned char[:, ::1] cap_rgb not None, const short[::1] label not None, float fb,
                   long long[::1] hits not None, long long[::1] written not None):
    """Draw cylinders 0..n-1 in that order (near to far), each in rows ``v0..v1`` and columns
    ``u0..u0+ncols``; column j of cylinder i uses per-column entry ``start[i] + j`` of ``t1``/``t2`` (ray
    entry and exit depth) and ``face`` (side colour), row v uses ``lo_rows``/``hi_rows[limit_row0[i] + v]``
    (the depths between which the ray is within the cylinder's height range). A pixel is hit where
    ``max(t1, lo) <= min(t2, hi)``; it is drawn where its disparity ``fb / max(t1, lo)`` is greater than
    what ``disparity`` holds: the side colour, or the cap colour where the ray meets the top or bottom
    (``t1 < lo``), and ``label`` into ``labels`` (if given). ``hits``/``written`` get, per cylinder, the
    pixels hit and the pixels drawn."""
    cdef Py_ssize_t n = start.shape[0]
    cdef Py_ssize_t i, v, j, c, u, row
    cdef float lo, hi, a, b, z, m, d
    cdef long long hit_count, written_count
    cdef bint with_labels = labels is not None
    cdef Py_ssize_t h = disparity.shape[0], w = disparity.shape[1]
    if not (image.shape[0] == h and image.shape[1] == w and image.shape[2] == 3
            and (not with_labels or (labels.shape[0] == h and labels.shape[1] == w))):
        raise ValueError("disparity, image and labels must be images of one size")
    for i in range(n):   # checked here, not per pixel: the loop below reads and writes without bounds checks
        if not (0 <= v0[i] and v1[i] <= h and 0 <= u0[i] and u0[i] + ncols[i] <= w and 0 <= start[i]
                and start[i] + ncols[i] <= min(t1.shape[0], t2.shape[0], face.shape[0]) and 0 <= limit_row0[i]
                and limit_row0[i] + v1[i] <= min(lo_rows.shape[0], hi_rows.shape[0])
                and i < min(u0.shape[0], ncols.shape[0], v0.shape[0], v1.shape[0], limit_row0.shape[0],
                            cap_rgb.shape[0], label.shape[0], hits.shape[0], written.shape[0])
                and cap_rgb.shape[1] >= 3 and face.shape[1] == 3):
            raise ValueError(f"cylinder {i}: its band or columns lie outside the arrays")
    cdef const float* t1p = &t1[0] if t1.shape[0] else NULL
    cdef const float* t2p = &t2[0] if t2.shape[0] else NULL
    cdef const unsigned char* facep = &face[0, 0] if face.shape[0] else NULL
    cdef float* drow
    cdef unsigned char* irow
    cdef short* lrow = NULL
    cdef unsigned char cap0, cap1, cap2
    cdef short lab
    cdef Py_ssize_t c0, first, cols
    for i in range(n):
        hit_count = 0
        written_count = 0
        c0, first, cols = u0[i], start[i], ncols[i]
        cap0, cap1, cap2, lab = cap_rgb[i, 0], cap_rgb[i, 1], cap_rgb[i, 2], label[i]
        for v in range(v0[i], v1[i]):
            row = limit_row0[i] + v
            lo = lo_rows[row]
            hi = hi_rows[row]
            drow = &disparity[v, c0]
            irow = &image[v, c0, 0]
            if with_labels:
                lrow = &labels[v, c0]
            for j in range(cols):
                c = first + j
                a = t1p[c]
                z = a if a > lo else lo          # numpy.maximum, NaN in lo included
                b = t2p[c]
                m = b if b < hi else hi          # numpy.minimum
                if not (z <= m):
                    continue
                hit_count += 1
                d = fb / z
                if not (d > drow[j]):
                    continue
                written_count += 1
                drow[j] = d
                if a < lo:
                    irow[3 * j] = cap0
                    irow[3 * j + 1] = cap1
                    irow[3 * j + 2] = cap2
                else:
                    irow[3 * j] = facep[3 * c]
                    irow[3 * j + 1] = facep[3 * c + 1]
                    irow[3 * j + 2] = facep[3 * c + 2]
                if with_labels:
                    lrow[j] = lab
        hits[i] = hit_count
        written[i] = written_count
