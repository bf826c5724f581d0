"""hearsee.fusion"""
