"""The study report: the paper's analyses, figures and the document writer."""
