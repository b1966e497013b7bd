"""What a design study asks: its file's keys (schema.py), read (reader.py) into the Study and its
types (study.py), its motions (motion.py) and the words its verdicts use (verdicts.py)."""
