"""The source paper (Yu et al. 2013): its embedded data reproduced, and the report beside its published claims."""
