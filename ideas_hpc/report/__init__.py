"""The report of a store (``ideas-hpc report``): text summary, figures, HTML page. It reads
stores and the campaign layer's vocabulary; nothing below imports it, so a change to a figure
or the page leaves the orchestration closed."""
