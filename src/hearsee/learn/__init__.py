"""hearsee.learn"""
