"""A reported number: the paper's value next to ours."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class Row:
    quantity: str
    paper: str        # as the paper states it ("" if it gives none)
    ours: float | str
    unit: str = ""
    note: str = ""    # the difference and its reason

    def cells(self) -> list[str]:
        ours = f"{self.ours:#.3g}".rstrip(".") if isinstance(self.ours, float) else str(self.ours)
        return [self.quantity, self.paper or "-", ours, self.unit, self.note]


def table(rows: list[Row], header=("quantity", "paper", "ours", "unit", "difference, reason")) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r.cells()) + " |" for r in rows]
    return "\n".join(lines)
