"""The run table, the contract between the navigation half and the learning half, and the paper's embedded runs."""
