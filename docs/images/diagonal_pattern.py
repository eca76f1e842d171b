#!/usr/bin/env python3
"""Writes diagonal_pattern.svg: the diagonal rule of docs/surface.md drawn on an 8 x 6-cell lattice.

Cell (i, j) is split along (i, j)-(i+1, j+1) when i + j is even ("main", shaded) and along
(i+1, j)-(i, j+1) when i + j is odd. x runs to the right, z down the page (image rows), as in a
heightmap image seen from above. Run: python3 docs/images/diagonal_pattern.py (no dependencies)."""
import os

CELLS_X, CELLS_Z, S, M = 8, 6, 64, 48   # cells, pixels per cell, margin
W, H = CELLS_X * S + 2 * M, CELLS_Z * S + 2 * M + 40

def px(i, j):
    return M + i * S, M + j * S

out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
       f'viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">',
       f'<rect width="{W}" height="{H}" fill="white"/>']
for j in range(CELLS_Z):
    for i in range(CELLS_X):
        x0, y0 = px(i, j)
        main = (i + j) % 2 == 0
        out.append(f'<rect x="{x0}" y="{y0}" width="{S}" height="{S}" '
                   f'fill="{"#dbe9f6" if main else "#fdf1d8"}" stroke="#888" stroke-width="1"/>')
        if main:   # (i, j)-(i+1, j+1)
            a, b = px(i, j), px(i + 1, j + 1)
        else:      # (i+1, j)-(i, j+1)
            a, b = px(i + 1, j), px(i, j + 1)
        out.append(f'<line x1="{a[0]}" y1="{a[1]}" x2="{b[0]}" y2="{b[1]}" '
                   f'stroke="{"#1f5fa8" if main else "#b5651d"}" stroke-width="2.5"/>')
        out.append(f'<text x="{x0 + S / 2}" y="{y0 + (S * 0.8 if main else S * 0.3)}" '
                   f'text-anchor="{"end" if main else "start"}" dx="{-6 if main else -22}" '
                   f'fill="#333">{i},{j}</text>')
# Sample indices along the edges.
for i in range(CELLS_X + 1):
    x, _ = px(i, 0)
    out.append(f'<text x="{x}" y="{M - 8}" text-anchor="middle" fill="#555">i={i}</text>')
for j in range(CELLS_Z + 1):
    _, y = px(0, j)
    out.append(f'<text x="{M - 8}" y="{y + 4}" text-anchor="end" fill="#555">j={j}</text>')
# Axes.
ax, ay = M + CELLS_X * S + 10, M + CELLS_Z * S + 10
out.append(f'<line x1="{M}" y1="{ay + 14}" x2="{M + 60}" y2="{ay + 14}" stroke="black" '
           f'marker-end="url(#arrow)"/><text x="{M + 66}" y="{ay + 18}">x (i)</text>')
out.append(f'<line x1="{M - 20}" y1="{M}" x2="{M - 20}" y2="{M + 60}" stroke="black" '
           f'marker-end="url(#arrow)"/><text x="{M - 26}" y="{M + 76}" text-anchor="middle">z (j)</text>')
out.insert(2, '<defs><marker id="arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
              'markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z"/></marker></defs>')
out.append(f'<text x="{M + 110}" y="{ay + 18}" fill="#1f5fa8">blue: i + j even, split (i,j)-(i+1,j+1)</text>')
out.append(f'<text x="{M + 110}" y="{ay + 34}" fill="#b5651d">orange: i + j odd, split (i+1,j)-(i,j+1)</text>')
out.append('</svg>')
path = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'diagonal_pattern.svg')
with open(path, 'w') as f:
    f.write('\n'.join(out) + '\n')
print(path)
