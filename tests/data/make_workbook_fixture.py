"""Writes cablab__testxpert_three_point_workbook.xlsx: the demo's testXpert three-point export
(raw_data/cable/three_point_2mm_1.TXT) as a lab would keep it in Excel, with openpyxl 3.1:
sheet 'Ergebnisse' (one results row, as testXpert's Excel export puts first), sheet 'Messwerte'
(the metadata lines as label/value/unit cells, the names and units rows, every sample as numeric
cells), and an empty sheet. Numbers are the file's own decimals (decimal comma read as point).

    python3 tests/data/make_workbook_fixture.py
"""
import openpyxl
from pathlib import Path

root = Path(__file__).resolve().parents[2]
src = (root / "raw_data/cable/three_point_2mm_1.TXT").read_text(encoding="latin-1").splitlines()


def cell(c):
    c = c.strip().strip('"')
    try:
        return float(c.replace(",", "."))
    except ValueError:
        return c


wb = openpyxl.Workbook()
res = wb.active
res.title = "Ergebnisse"
res.append(["Probe", "EI", "Fmax"])
res.append(["", "N m²", "N"])
res.append(["cable2.8-B3-2-1", None, None])
ws = wb.create_sheet("Messwerte")
for line in src:
    ws.append([cell(c) for c in line.split("\t")])
wb.create_sheet("Notizen")
wb.save(Path(__file__).with_name("cablab__testxpert_three_point_workbook.xlsx"))
