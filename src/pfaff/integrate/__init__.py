"""The integration stage: ``simulate``, projection, Baumgarte, IDA, the float DOP853, initial states."""
