"""``tasks.core.style``'s lean PDF font subsets: the same glyphs, without layout tables."""

import string

from fontTools import subset as ft_subset
from matplotlib import font_manager
from matplotlib.backends import _backend_pdf_ps as pdf_ps
from matplotlib.ft2font import FT2Font

from tasks.core import style

TEXT = string.ascii_letters + string.digits + " ()[]-+.,:/%°µσ−–"


def _subset(lean: bool, monkeypatch):
    monkeypatch.setattr(style, "LEAN_PDF_FONTS", lean)
    path = font_manager.findfont("DejaVu Sans")
    ft = FT2Font(path)
    gids = {ft.get_char_index(ord(c)) for c in TEXT}
    fp = pdf_ps.FontPath(path, 0) if hasattr(pdf_ps, "FontPath") else path
    with style._lean_pdf_fonts():
        with pdf_ps.get_glyphs_subset(fp, gids) as res:
            font = res.font
            names = [ft.get_glyph_name(g) for g in sorted(gids)]
            glyf, hmtx = font["glyf"], font["hmtx"]
            outlines = {}
            for n in names:
                g = glyf[n]
                g.expand(glyf)
                coords = list(g.getCoordinates(glyf)[0]) if g.numberOfContours else []
                outlines[n] = (coords, hmtx[n])
            return set(font.keys()), outlines


def test_lean_subset_keeps_every_glyph_and_drops_layout_tables(monkeypatch) -> None:
    tables, outlines = _subset(False, monkeypatch)
    lean_tables, lean_outlines = _subset(True, monkeypatch)
    assert {"GSUB", "GPOS"} <= tables  # matplotlib's own subset keeps them
    assert not lean_tables & set(style._LAYOUT_TABLES)
    assert tables - lean_tables <= set(style._LAYOUT_TABLES)  # nothing else is dropped
    assert lean_outlines == outlines  # the same outlines and advance widths, glyph by glyph


def test_backend_restored_after_the_block() -> None:
    with style._lean_pdf_fonts():
        assert isinstance(pdf_ps.subset, style._LeanSubset)
    assert pdf_ps.subset is ft_subset
