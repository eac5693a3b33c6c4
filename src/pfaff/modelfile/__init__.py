"""Model files: systems described in TOML (:mod:`pfaff.modelfile.load`)."""

from pfaff.modelfile.load import ModelFile, ModelFileError, load_model

__all__ = ["ModelFile", "ModelFileError", "load_model"]
