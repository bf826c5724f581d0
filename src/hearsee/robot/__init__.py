"""The robot: hear a person, turn to them, see and verify them, track them in 3D (issue 8).

``scenario`` describes a world (room, robot head, people, objects, noise) in YAML;
``pipeline`` runs the full perception loop on a simulated scenario; ``report`` writes the HTML
report, the JSON log and the summary; ``evaluate`` runs many random scenarios in parallel.
"""
