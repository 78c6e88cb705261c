// netlab score (placeholder until the command lands)
