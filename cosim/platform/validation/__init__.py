"""The validation report: the source papers' results reproduced from the shipped scenes and FMUs
(docs/validation.md, rebuilt by `python -m cosim validate`). Each study returns its numbers as
Rows (the paper's value, ours, and why they differ) and writes its figures; tests assert the key
numbers through the same functions."""
