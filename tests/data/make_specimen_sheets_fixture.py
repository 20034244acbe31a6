"""Writes cablab__bluehill_specimen_sheets.xlsx: a workbook of three tension specimens, a sheet
each with the same columns (as Bluehill's Excel export keeps a series), and a results sheet, with
openpyxl 3.1. Written by this script, not by a machine: the values are exact lines with a small
deterministic wiggle, so the stiffness each sheet must give is known.

    sheet 'Results'     one row per specimen (a summary: no test of its own)
    sheet 'Specimen 1'  length 100 mm, diameter 2 mm, k = 1.0e5 N/m -> (EA) = 1.0e4 N, 200 rows
    sheet 'Specimen 2'  length 100 mm, diameter 2 mm, k = 1.5e5 N/m -> (EA) = 1.5e4 N, 300 rows
    sheet 'Specimen 3'  length 120 mm, diameter 2.5 mm, k = 2.0e5 N/m -> (EA) = 2.4e4 N, 200 rows

    python3 tests/data/make_specimen_sheets_fixture.py
"""
import openpyxl
from pathlib import Path

SPECIMENS = [
    ("Specimen 1", 100.0, 2.0, 1.0e5, 200),
    ("Specimen 2", 100.0, 2.0, 1.5e5, 300),
    ("Specimen 3", 120.0, 2.5, 2.0e5, 200),
]

wb = openpyxl.Workbook()
res = wb.active
res.title = "Results"
res.append(["Specimen", "Length", "Diameter", "Maximum load"])
res.append(["", "(mm)", "(mm)", "(N)"])
for name, l, d, k, n in SPECIMENS:
    res.append([name, l, d, round(k * 1e-3, 3)])
for name, l, d, k, n in SPECIMENS:
    ws = wb.create_sheet(name)
    ws.append(["Test type", "Tension"])
    ws.append(["Length", l, "mm"])
    ws.append(["Diameter", d, "mm"])
    ws.append([])
    ws.append(["Time", "Extension", "Load"])
    ws.append(["(s)", "(mm)", "(N)"])
    for i in range(n + 1):
        u = 1e-3 * i / n  # m, to 1 mm
        wiggle = 0.5 * ((i * 7919) % 5 - 2)  # N
        ws.append([round(0.1 * i, 2), round(u * 1e3, 6), round(k * u + wiggle, 4)])
wb.save(Path(__file__).with_name("cablab__bluehill_specimen_sheets.xlsx"))
