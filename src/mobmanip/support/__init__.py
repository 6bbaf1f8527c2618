"""What every layer leans on: files written atomically, stated numeric ranges, shared tolerances."""
