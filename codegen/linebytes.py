"""Program lines (and ``correct``'s CSV lines) built by numpy as bytes, for jobs of 100,000 holes
without a Python format call per number: a "line image" (n, L) uint8 holds in row i the text of
item i (one hole: one or more lines), its numbers and texts in fixed-width cells padded with NUL
between the constant text of a template; dropping every NUL gives the lines. No text of a
program holds a NUL.

- ``number_cells(values, places)``: the ``fixed`` text of every value (any shape ``s``) as cells
  (*s, w) uint8, NUL-padded on the left (``textsafe.fixed_bytes``);
- ``text_cells(texts)``: ASCII texts (n,) as cells (n, w) uint8, NUL-padded on the right;
- ``line_image(template, cells)``: the image (n, L) of a template, ASCII text with ``SLOT`` where
  each cell (n, w_k) goes, in order;
- ``merge_images(masks, images)``: one image (n, L) of items of several templates, each image
  (count, L_k) holding the rows of its mask (n,) bool;
- ``image_bytes(image)``: the text of an image's rows in order, NULs dropped (ASCII bytes).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from accugrid.infra.textsafe import fixed_bytes

__all__ = ["SLOT", "image_bytes", "line_image", "merge_images", "number_cells", "text_cells"]

SLOT = "\0"  # where a cell goes in a template of ``line_image``


def number_cells(values: np.ndarray, places: int) -> np.ndarray:
    """``fixed(v, places)`` of every value (any shape s) as cells (*s, w) uint8, the text's ASCII
    bytes NUL-padded on the left (w: the longest text). Raises ValueError for NaN or infinity."""
    values = np.asarray(values, dtype=float)
    cells, _ = fixed_bytes(values.reshape(-1), places)
    return cells.reshape(*values.shape, cells.shape[1])


def text_cells(texts: Sequence[str]) -> np.ndarray:
    """ASCII texts (n,) without NUL as cells (n, w) uint8, NUL-padded on the right (w: the longest
    text, at least 1). UnicodeEncodeError for a text that is not ASCII."""
    array = np.array(texts, dtype="S") if len(texts) else np.zeros(0, "S1")
    return array.view(np.uint8).reshape(len(texts), array.dtype.itemsize)


def line_image(template: str, cells: Sequence[np.ndarray]) -> np.ndarray:
    """The image (n, L) uint8 of ``template`` (ASCII, one item's text with ``SLOT`` where each of
    ``cells`` goes, in order) filled with ``cells``, each (n, w_k) uint8 with each row's bytes
    adjacent (a C-contiguous last axis, as the cells above and their row selections have): every
    row is the constant text with the item's cells in their slots."""
    texts = template.encode("ascii").split(SLOT.encode())
    if len(texts) != len(cells) + 1 or not cells:
        raise ValueError(f"template with {len(texts) - 1} slots for {len(cells)} cells")
    widths = [cell.shape[1] for cell in cells]
    row = np.zeros(sum(map(len, texts)) + sum(widths), np.uint8)
    at, slots = 0, []
    for text, width in zip(texts, [*widths, 0], strict=True):
        row[at : at + len(text)] = np.frombuffer(text, np.uint8)
        at += len(text)
        slots.append(at)
        at += width
    image = np.empty((len(cells[0]), len(row)), np.uint8)
    image[:] = row
    for at, width, cell in zip(slots, widths, cells, strict=False):
        if width:  # each row's cell as one element: a copy per row, not per byte
            whole = f"V{width}"
            image[:, at : at + width].view(whole)[:, 0] = cell.view(whole)[:, 0]
    return image


def merge_images(masks: Sequence[np.ndarray], images: Sequence[np.ndarray]) -> np.ndarray:
    """One image (n, L) of n items whose rows come from several images: ``images[k]``
    (count_k, L_k) holds, in order, the rows where ``masks[k]`` (n,) bool is set; the masks do not
    overlap; L is the widest L_k, the rest of a row NUL."""
    width = max((image.shape[1] for image in images), default=0)
    merged = np.zeros((len(masks[0]), width), np.uint8)
    for mask, image in zip(masks, images, strict=True):
        merged[mask, : image.shape[1]] = image
    return merged


def image_bytes(image: np.ndarray) -> bytes:
    """The text of an image's rows, in order, with every NUL dropped."""
    return image.tobytes().translate(None, b"\0")
