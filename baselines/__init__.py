"""Every synthesizer other than the DAM: references, classical models, neural predictors."""
